#pragma once
// Path math shared by the carrier paths (sim/rig/carrier_paths.cpp): Taylor jets (a signal and its first three
// time derivatives, so every path gives exact velocity, acceleration and jerk), the cubic-B-spline kernel that
// smooths piecewise plans in closed form, and natural cubic splines. Header-only; pure functions and immutable
// value types (thread-safe). docs/motion.md derives them.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "sim/rig/base_motion.hpp"

namespace rotolidar::sim::path_math {

// ---- Taylor jets: a signal and its first three time derivatives, with the arithmetic the paths need. ----

/// f(t0 + e) = c0 + c1 e + c2 e^2 + c3 e^3 + O(e^4) (normalised Taylor coefficients).
struct Jet {
  std::array<double, 4> c{};
  static Jet Constant(double v) { return Jet{{v, 0.0, 0.0, 0.0}}; }
  static Jet FromDerivatives(double f, double d1, double d2, double d3) { return Jet{{f, d1, d2 / 2, d3 / 6}}; }
};
inline Jet operator+(Jet a, const Jet& b) {
  for (int k = 0; k < 4; ++k) a.c[k] += b.c[k];
  return a;
}
inline Jet operator-(Jet a, const Jet& b) {
  for (int k = 0; k < 4; ++k) a.c[k] -= b.c[k];
  return a;
}
inline Jet operator*(double s, Jet a) {
  for (double& v : a.c) v *= s;
  return a;
}
inline Jet operator*(const Jet& a, const Jet& b) {
  Jet r;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j <= k; ++j) r.c[k] += a.c[j] * b.c[k - j];
  return r;
}
inline Jet Divide(const Jet& a, const Jet& b) {
  Jet q;
  for (int k = 0; k < 4; ++k) {
    double s = a.c[k];
    for (int j = 1; j <= k; ++j) s -= b.c[j] * q.c[k - j];
    q.c[k] = s / b.c[0];
  }
  return q;
}
/// d/dt as a jet (its top coefficient is unknown and left 0: valid to second order).
inline Jet Derivative(const Jet& f) { return Jet{{f.c[1], 2 * f.c[2], 3 * f.c[3], 0.0}}; }
inline void SinCos(const Jet& f, Jet* s, Jet* c) {
  *s = Jet::Constant(std::sin(f.c[0]));
  *c = Jet::Constant(std::cos(f.c[0]));
  for (int k = 1; k < 4; ++k) {  // s' = c f', c' = -s f'
    double ds = 0, dc = 0;
    for (int j = 1; j <= k; ++j) ds += j * f.c[j] * c->c[k - j], dc -= j * f.c[j] * s->c[k - j];
    s->c[k] = ds / k, c->c[k] = dc / k;
  }
}
/// The angle of (x, y) (wrapped value, exact derivatives); (x, y) must not vanish.
Jet Atan2(const Jet& y, const Jet& x) {
  const Jet rate = Divide(x * Derivative(y) - y * Derivative(x), x * x + y * y);
  Jet a = Jet::Constant(std::atan2(y.c[0], x.c[0]));
  for (int k = 1; k < 4; ++k) a.c[k] = rate.c[k - 1] / k;
  return a;
}
/// g(u(t)) for a function g with derivatives g[0..3] at u(t0).
inline Jet Compose(const std::array<double, 4>& g, const Jet& u) {
  Jet d = u;
  d.c[0] = 0.0;
  const Jet d2 = d * d, d3 = d2 * d;
  return Jet::Constant(g[0]) + g[1] * d + (0.5 * g[2]) * d2 + (g[3] / 6.0) * d3;
}
/// A sin(w t + phase) as a jet at t.
inline Jet Sinusoid(double amplitude, double w, double phase, double t) {
  const double s = std::sin(w * t + phase), c = std::cos(w * t + phase);
  return Jet::FromDerivatives(amplitude * s, amplitude * w * c, -amplitude * w * w * s, -amplitude * w * w * w * c);
}

/// Kinematics of R_world_base = Rz(yaw) Ry(pitch) Rx(roll) at position p: body rates from the ZYX Euler rates.
inline BaseKinematics KinematicsFromJets(const std::array<Jet, 3>& p, const Jet& yaw, const Jet& pitch, const Jet& roll) {
  Jet sr, cr, sp, cp;
  SinCos(roll, &sr, &cr);
  SinCos(pitch, &sp, &cp);
  const Jet dr = Derivative(roll), dp = Derivative(pitch), dy = Derivative(yaw);
  const std::array<Jet, 3> w = {dr - dy * sp, dp * cr + dy * sr * cp, dy * cr * cp - dp * sr};
  BaseKinematics k;
  k.T_world_base.linear() = (Eigen::AngleAxisd(yaw.c[0], Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch.c[0], Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(roll.c[0], Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  for (int i = 0; i < 3; ++i) {
    k.T_world_base.translation()[i] = p[size_t(i)].c[0];
    k.v_world_mps[i] = p[size_t(i)].c[1];
    k.a_world_mps2[i] = 2.0 * p[size_t(i)].c[2];
    k.omega_base_radps[i] = w[size_t(i)].c[0];
    k.alpha_base_radps2[i] = w[size_t(i)].c[1];
  }
  return k;
}

// ---- Kernel smoothing of piecewise-polynomial plans. ----

/// The centred cubic B-spline kernel K of width w (support [-w/2, w/2], knot spacing h = w/4, C2, unit area)
/// and its repeated antiderivatives: D(m, x) is the (m+1)-fold antiderivative of K (m = -1: K; m = -2, -3:
/// K', K''). With truncated powers: D(m, x) = h^m sum_i (-1)^i C(4,i) (x/h + 2 - i)_+^(4+m) / (4+m)!.
class Kernel {
 public:
  explicit Kernel(double width_s) : h_(width_s / 4.0) {}
  double half_width() const { return 2.0 * h_; }
  double D(int m, double x) const {
    const double u = x / h_;
    if (u <= -2.0) return 0.0;
    if (u >= 2.0) return m == 0 ? 1.0 : m == 1 ? x : m == 2 ? 0.5 * x * x + h_ * h_ / 6.0 : 0.0;
    static const double kBinomial[5] = {1, 4, 6, 4, 1};
    static const double kFactorial[7] = {1, 1, 2, 6, 24, 120, 720};
    const int n = 4 + m;
    double sum = 0.0;
    for (int i = 0; i < 5; ++i) {
      const double a = u + 2.0 - i;
      if (a > 0.0) sum += (i % 2 ? -kBinomial[i] : kBinomial[i]) * std::pow(a, n);
    }
    return sum / kFactorial[n] * std::pow(h_, m);
  }

 private:
  double h_;
};

struct Jump {
  double t_s;
  Eigen::Vector3d delta;
};

/// f0(t) = base + sum_k delta_k (t - t_k)_+^order / order! (order 0: steps, 1: slope jumps, 2: curvature jumps),
/// convolved with the Kernel: exact, C(order + 2), only jumps within half a width of t cost anything.
class SmoothedPlan {
 public:
  SmoothedPlan(int order, double width_s, const Eigen::Vector3d& base, std::vector<Jump> jumps)
      : order_(order), kernel_(width_s), base_(base), jumps_(std::move(jumps)) {
    Eigen::Vector3d s[3] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    for (const Jump& j : jumps_) {
      for (int p = 0; p < 3; ++p) prefix_[p].push_back(s[p]);
      s[0] += j.delta, s[1] += j.delta * j.t_s, s[2] += j.delta * j.t_s * j.t_s;
    }
    for (int p = 0; p < 3; ++p) prefix_[p].push_back(s[p]);
  }
  std::array<Jet, 3> Eval(double t) const {
    const double hw = kernel_.half_width();
    // [lo, hi): the jumps with |t - t_k| < w/2; those before lo are at or past w/2 behind t.
    const size_t lo = size_t(std::upper_bound(jumps_.begin(), jumps_.end(), t - hw,
                                              [](double v, const Jump& j) { return v < j.t_s; }) - jumps_.begin());
    const size_t hi = size_t(std::lower_bound(jumps_.begin(), jumps_.end(), t + hw,
                                              [](const Jump& j, double v) { return j.t_s < v; }) - jumps_.begin());
    // Jumps at or before t - w/2 act as the plain polynomial (plus the kernel's variance for order 2).
    const Eigen::Vector3d &s0 = prefix_[0][lo], &s1 = prefix_[1][lo], &s2 = prefix_[2][lo];
    Eigen::Vector3d v[4] = {base_, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    if (order_ == 0) v[0] += s0;
    if (order_ == 1) v[0] += t * s0 - s1, v[1] = s0;
    if (order_ == 2) {
      const double h = hw / 2.0;
      v[0] += 0.5 * (t * t * s0 - 2.0 * t * s1 + s2) + (h * h / 6.0) * s0;
      v[1] = t * s0 - s1;
      v[2] = s0;
    }
    for (size_t k = lo; k < hi; ++k)
      for (int j = 0; j < 4; ++j) v[j] += jumps_[k].delta * kernel_.D(order_ - j, t - jumps_[k].t_s);
    std::array<Jet, 3> out;
    for (int i = 0; i < 3; ++i) out[size_t(i)] = Jet::FromDerivatives(v[0][i], v[1][i], v[2][i], v[3][i]);
    return out;
  }

 private:
  int order_;
  Kernel kernel_;
  Eigen::Vector3d base_;
  std::vector<Jump> jumps_;
  std::vector<Eigen::Vector3d> prefix_[3];  ///< sums over jumps before index i of delta, delta t, delta t^2
};

// ---- Natural cubic splines (C2, exact through the knots, linear extrapolation outside: still C2). ----

class CubicSpline {
 public:
  /// x strictly increasing (n >= 2), y: n rows, one column per dimension.
  CubicSpline(std::vector<double> x, Eigen::MatrixXd y) : x_(std::move(x)), y_(std::move(y)) {
    const long n = long(x_.size());
    m_ = Eigen::MatrixXd::Zero(n, y_.cols());
    if (n < 3) return;
    // Thomas algorithm on h_(i-1) M_(i-1) + 2 (h_(i-1) + h_i) M_i + h_i M_(i+1) = 6 (slope_i - slope_(i-1)).
    std::vector<double> cp(size_t(n), 0.0);
    Eigen::MatrixXd rp = Eigen::MatrixXd::Zero(n, y_.cols());
    for (long i = 1; i < n - 1; ++i) {
      const double h0 = x_[size_t(i)] - x_[size_t(i - 1)], h1 = x_[size_t(i + 1)] - x_[size_t(i)];
      const Eigen::RowVectorXd r = 6.0 * ((y_.row(i + 1) - y_.row(i)) / h1 - (y_.row(i) - y_.row(i - 1)) / h0);
      const double denom = 2.0 * (h0 + h1) - h0 * cp[size_t(i - 1)];
      cp[size_t(i)] = h1 / denom;
      rp.row(i) = (r - h0 * rp.row(i - 1)) / denom;
    }
    for (long i = n - 2; i >= 1; --i) m_.row(i) = rp.row(i) - cp[size_t(i)] * m_.row(i + 1);
  }
  /// Derivatives 0..3 (columns) of every dimension (rows) at s.
  Eigen::MatrixX4d Eval(double s) const {
    const size_t n = x_.size();
    const bool before = s < x_.front(), after = s > x_.back();
    size_t i = before ? 0 : after ? n - 2 : size_t(std::upper_bound(x_.begin(), x_.end(), s) - x_.begin()) - 1;
    i = std::min(i, n - 2);
    const double h = x_[i + 1] - x_[i];
    const double t = after ? h : before ? 0.0 : s - x_[i];
    const Eigen::VectorXd A = m_.row(long(i)).transpose(), B = m_.row(long(i + 1)).transpose();
    const Eigen::VectorXd y0 = y_.row(long(i)).transpose(), y1 = y_.row(long(i + 1)).transpose();
    const Eigen::VectorXd b = (y1 - y0) / h - h * (2.0 * A + B) / 6.0;
    Eigen::MatrixX4d out(y_.cols(), 4);
    out.col(0) = y0 + b * t + A * (t * t / 2) + (B - A) * (t * t * t / (6 * h));
    out.col(1) = b + A * t + (B - A) * (t * t / (2 * h));
    out.col(2) = A + (B - A) * (t / h);
    out.col(3) = (B - A) / h;
    if (before || after) {  // natural ends: M = 0 there, so the straight continuation keeps C2
      out.col(0) += out.col(1) * (s - (after ? x_.back() : x_.front()));
      out.col(2).setZero();
      out.col(3).setZero();
    }
    return out;
  }

 private:
  std::vector<double> x_;
  Eigen::MatrixXd y_, m_;
};

inline double WrapPi(double a) { return std::remainder(a, 2.0 * M_PI); }

}  // namespace rotolidar::sim::path_math
