#include "bench/eval/allan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "core/util/log.hpp"

namespace rotolidar::bench {
namespace {

/// Log-spaced unique cluster sizes in [1, m_max].
std::vector<long> ClusterSizes(long m_max, int points_per_decade) {
  std::vector<long> sizes;
  for (int i = 0;; ++i) {
    const long m = std::lround(std::pow(10.0, double(i) / points_per_decade));
    if (m > m_max) break;
    if (sizes.empty() || m > sizes.back()) sizes.push_back(m);
  }
  return sizes;
}

/// Least squares of A x = b restricted to the columns in `mask`; +inf cost when a coefficient is negative.
double SubsetFit(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, unsigned mask, Eigen::VectorXd* x) {
  std::vector<int> cols;
  for (int c = 0; c < A.cols(); ++c)
    if (mask & (1u << c)) cols.push_back(c);
  Eigen::MatrixXd As(A.rows(), Eigen::Index(cols.size()));
  for (size_t j = 0; j < cols.size(); ++j) As.col(Eigen::Index(j)) = A.col(cols[j]);
  const Eigen::VectorXd xs = As.colPivHouseholderQr().solve(b);
  x->setZero(A.cols());
  for (size_t j = 0; j < cols.size(); ++j) {
    if (!(xs[Eigen::Index(j)] >= 0)) return std::numeric_limits<double>::infinity();
    (*x)[cols[j]] = xs[Eigen::Index(j)];
  }
  return (A * *x - b).squaredNorm();
}

/// Non-negative least squares for a handful of unknowns: the best of all column subsets.
Eigen::VectorXd SmallNnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  Eigen::VectorXd best = Eigen::VectorXd::Zero(A.cols()), x;
  double best_cost = std::numeric_limits<double>::infinity();
  for (unsigned mask = 1; mask < (1u << A.cols()); ++mask) {
    const double cost = SubsetFit(A, b, mask, &x);
    if (cost < best_cost) best_cost = cost, best = x;
  }
  return best;
}

}  // namespace

AllanCurve OverlappingAllanDeviation(const std::vector<double>& series, double rate_hz, const AllanOptions& options) {
  ROTOLIDAR_CHECK(rate_hz > 0 && std::isfinite(rate_hz), "rate_hz " << rate_hz);
  ROTOLIDAR_CHECK(options.points_per_decade > 0, "points_per_decade " << options.points_per_decade);
  AllanCurve curve;
  const long n = long(series.size());
  curve.samples = n;
  if (n < 4) return curve;
  const double tau0 = 1.0 / rate_hz;
  // Integrate the mean-free series (the mean cancels in the second difference; removing it keeps theta small).
  long double mean = 0;
  for (double y : series) mean += y;
  mean /= n;
  std::vector<double> theta(size_t(n) + 1, 0.0);
  long double acc = 0;
  for (long k = 0; k < n; ++k) {
    acc += (series[size_t(k)] - mean) * tau0;
    theta[size_t(k) + 1] = double(acc);
  }
  const long m_max = std::max(1L, long(options.max_cluster_fraction * double(n)));
  for (long m : ClusterSizes(std::min(m_max, (n - 1) / 2), options.points_per_decade)) {
    const long terms = n + 1 - 2 * m;
    long double sum = 0;
    for (long k = 0; k < terms; ++k) {
      const double d = theta[size_t(k + 2 * m)] - 2.0 * theta[size_t(k + m)] + theta[size_t(k)];
      sum += d * d;
    }
    const double tau = double(m) * tau0;
    curve.tau_s.push_back(tau);
    curve.adev.push_back(std::sqrt(double(sum / terms) / (2.0 * tau * tau)));
    curve.cluster_size.push_back(m);
  }
  return curve;
}

AllanFit FitAllan(const AllanCurve& curve, const AllanOptions& options) {
  AllanFit fit;
  const int points = int(curve.tau_s.size());
  if (points < 3 || curve.samples <= 0) return fit;
  const int unknowns = options.fit_bias_instability ? 3 : 2;
  const double kFloor = 2.0 * std::log(2.0) / M_PI;  // AVAR of a flicker floor B: (2 ln2 / pi) B^2
  Eigen::VectorXd avar(points), model(points);
  Eigen::MatrixXd basis(points, unknowns);
  for (int i = 0; i < points; ++i) {
    const double tau = curve.tau_s[size_t(i)];
    avar[i] = curve.adev[size_t(i)] * curve.adev[size_t(i)];
    basis(i, 0) = 1.0 / tau;
    basis(i, 1) = tau / 3.0;
    if (unknowns == 3) basis(i, 2) = kFloor;
  }
  // Iteratively reweighted: each row divided by (model value * relative uncertainty sqrt(m / N)); the first pass
  // uses the measured AVAR in place of the model.
  model = avar;
  Eigen::VectorXd x;
  for (int iteration = 0; iteration < 4; ++iteration) {
    Eigen::MatrixXd A(points, unknowns);
    Eigen::VectorXd b(points);
    for (int i = 0; i < points; ++i) {
      const double rel = std::sqrt(double(curve.cluster_size[size_t(i)]) / double(curve.samples));
      const double scale = 1.0 / (std::max(model[i], 1e-300) * rel);
      A.row(i) = basis.row(i) * scale;
      b[i] = avar[i] * scale;
    }
    x = SmallNnls(A, b);
    model = basis * x;
    if (!(model.minCoeff() > 0)) model = avar;  // degenerate fit: keep measured weights
  }
  fit.converged = true;
  fit.points = points;
  fit.white_density = std::sqrt(x[0]);
  fit.random_walk = std::sqrt(x[1]);
  if (unknowns == 3) fit.bias_instability = std::sqrt(x[2]);
  double sq = 0;
  for (int i = 0; i < points; ++i) {
    const double r = model[i] > 0 && avar[i] > 0 ? std::log(model[i] / avar[i]) : 0.0;
    sq += r * r;
  }
  fit.rms_log_residual = std::sqrt(sq / points);
  return fit;
}

AllanReport FitImuAllan(const std::vector<ImuSample>& samples, double rate_hz, const AllanOptions& options) {
  AllanReport report;
  report.rate_hz = rate_hz;
  report.duration_s = double(samples.size()) / rate_hz;
  std::vector<double> series(samples.size());
  for (int axis = 0; axis < 3; ++axis) {
    for (bool gyro : {true, false}) {
      for (size_t i = 0; i < samples.size(); ++i)
        series[i] = gyro ? samples[i].gyro_radps[axis] : samples[i].accel_mps2[axis];
      AllanAxis& out = gyro ? report.gyro[size_t(axis)] : report.accel[size_t(axis)];
      out.curve = OverlappingAllanDeviation(series, rate_hz, options);
      out.fit = FitAllan(out.curve, options);
    }
  }
  return report;
}

void WriteAllanTable(std::ostream& out, const AllanReport& report) {
  out << "tau_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n";
  const AllanCurve& ref = report.gyro[0].curve;
  const auto old_precision = out.precision(10);
  for (size_t i = 0; i < ref.tau_s.size(); ++i) {
    out << ref.tau_s[i];
    for (const auto* sensor : {&report.gyro, &report.accel})
      for (const AllanAxis& axis : *sensor) out << ',' << (i < axis.curve.adev.size() ? axis.curve.adev[i] : NAN);
    out << '\n';
  }
  const char* names[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a)
    for (bool gyro : {true, false}) {
      const AllanFit& f = gyro ? report.gyro[size_t(a)].fit : report.accel[size_t(a)].fit;
      out << "# fit " << (gyro ? "gyro_" : "accel_") << names[a] << ": noise_density " << f.white_density
          << " random_walk " << f.random_walk << " bias_instability " << f.bias_instability << " points "
          << f.points << " rms_log_residual " << f.rms_log_residual << '\n';
    }
  out.precision(old_precision);
}

}  // namespace rotolidar::bench
