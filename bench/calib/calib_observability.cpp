// Observability of the rotor calibration from the Gauss-Newton Hessian at the estimate (rotor_calib.hpp).
// The Jacobian comes from central differences of residuals whose plane normal is refitted (PCA) to the
// transformed neighbours, so a rigid motion of the whole static cloud (the gauge: a rotation about the motor axis,
// a shift along it) leaves every residual unchanged and shows as a direction without information.
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "bench/calib/rotor_calib.hpp"

namespace rotolidar::bench {
namespace {

using HessianMatrix = Eigen::Matrix<double, kCalibParamCount, kCalibParamCount>;

/// The residual of `a` with its normal refitted to the neighbours under `d` (sign of the stored normal).
double RefittedResidual(const std::vector<ResidualPoint>& table, const double* t0, const PlaneAssociation& a,
                        const RotorCalibParams& d) {
  Eigen::Vector3d q, mean = Eigen::Vector3d::Zero();
  MotorPoint(table[a.query], t0, d.lever_m.data(), d.tilt_rad.data(), d.encoder_zero_rad, d.time_offset_s, q.data());
  std::vector<Eigen::Vector3d> p(a.neighbours.size());
  for (std::size_t j = 0; j < p.size(); ++j) {
    MotorPoint(table[a.neighbours[j]], t0, d.lever_m.data(), d.tilt_rad.data(), d.encoder_zero_rad, d.time_offset_s,
               p[j].data());
    mean += p[j];
  }
  mean /= double(p.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& v : p) cov += (v - mean) * (v - mean).transpose();
  Eigen::Vector3d n = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  if (n.dot(a.normal_motor) < 0) n = -n;
  return n.dot(q - mean);
}

/// Central-difference step of each parameter [m, rad or s]: residuals move ~1e-5 m, far above double rounding
/// (the time offset's 40 us turns the rotor by 1e-4 rad at the default 2.6 rad/s).
double StepOf(int param) { return param == kTimeOffset ? 4e-5 : 1e-4; }
/// A parameter is observable when its sigma is below these (the size of the errors the calibration corrects):
/// the gauge directions come out many orders of magnitude larger (sigmas of 1e3..1e8 m or rad on the twin).
constexpr double kObservableSigmaM = 0.01, kObservableSigmaRad = 0.01, kObservableSigmaS = 1e-3;

double ObservableSigma(int param) {
  return param < kTiltX ? kObservableSigmaM : param == kTimeOffset ? kObservableSigmaS : kObservableSigmaRad;
}

/// Conditional information of `p` given the estimated parameters other than p (Schur complement) [1/unit^2].
double ConditionalInformation(const HessianMatrix& H, int p, const std::array<bool, kCalibParamCount>& estimate) {
  std::vector<int> others;
  for (int k = 0; k < kCalibParamCount; ++k)
    if (estimate[k] && k != p) others.push_back(k);
  if (others.empty()) return H(p, p);
  const int m = int(others.size());
  Eigen::MatrixXd Hoo(m, m);
  Eigen::VectorXd Hop(m);
  for (int i = 0; i < m; ++i) {
    Hop[i] = H(others[i], p);
    for (int j = 0; j < m; ++j) Hoo(i, j) = H(others[i], others[j]);
  }
  return H(p, p) - Hop.dot(Hoo.ldlt().solve(Hop));
}

}  // namespace

void ComputeObservability(const std::vector<ResidualPoint>& table, const double* t0,
                          const std::vector<PlaneAssociation>& associations, const RotorCalibOptions& options,
                          RotorCalibResult* result) {
  const RotorCalibParams& x = result->correction;
  HessianMatrix H = HessianMatrix::Zero();
  double weighted_sq = 0.0;
  for (const PlaneAssociation& a : associations) {
    const double r = RefittedResidual(table, t0, a, x);
    const double w = std::abs(r) <= options.huber_m ? 1.0 : options.huber_m / std::abs(r);
    Eigen::Matrix<double, kCalibParamCount, 1> J;
    for (int p = 0; p < kCalibParamCount; ++p) {
      RotorCalibParams plus = x, minus = x;
      plus.Set(p, x.Get(p) + StepOf(p));
      minus.Set(p, x.Get(p) - StepOf(p));
      J[p] = (RefittedResidual(table, t0, a, plus) - RefittedResidual(table, t0, a, minus)) /
             (2.0 * StepOf(p));
    }
    H += w * J * J.transpose();
    weighted_sq += w * r * r;
  }
  int free = 0;
  for (bool e : options.estimate) free += e ? 1 : 0;
  const double dof = std::max(1.0, double(associations.size()) - free);
  const double s2 = weighted_sq / dof;
  result->hessian = H;
  result->residual_sigma_m = std::sqrt(s2);
  for (int p = 0; p < kCalibParamCount; ++p) {
    ParamObservability& o = result->observability[p];
    o.estimated = options.estimate[p];
    const double info = ConditionalInformation(H, p, options.estimate);
    o.independence = H(p, p) > 0.0 ? std::max(0.0, info / H(p, p)) : 0.0;
    o.sigma = info > 0.0 ? std::sqrt(s2 / info) : std::numeric_limits<double>::infinity();
    o.observable = o.independence > 1e-3 && o.sigma < ObservableSigma(p);
  }
}

}  // namespace rotolidar::bench
