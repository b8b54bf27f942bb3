#include "sim/rig/carrier_paths.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace rotolidar::sim {
namespace {

// ---- Taylor jets: a signal and its first three time derivatives, with the arithmetic the paths need. ----

/// f(t0 + e) = c0 + c1 e + c2 e^2 + c3 e^3 + O(e^4) (normalised Taylor coefficients).
struct Jet {
  std::array<double, 4> c{};
  static Jet Constant(double v) { return Jet{{v, 0.0, 0.0, 0.0}}; }
  static Jet FromDerivatives(double f, double d1, double d2, double d3) { return Jet{{f, d1, d2 / 2, d3 / 6}}; }
};
Jet operator+(Jet a, const Jet& b) {
  for (int k = 0; k < 4; ++k) a.c[k] += b.c[k];
  return a;
}
Jet operator-(Jet a, const Jet& b) {
  for (int k = 0; k < 4; ++k) a.c[k] -= b.c[k];
  return a;
}
Jet operator*(double s, Jet a) {
  for (double& v : a.c) v *= s;
  return a;
}
Jet operator*(const Jet& a, const Jet& b) {
  Jet r;
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j <= k; ++j) r.c[k] += a.c[j] * b.c[k - j];
  return r;
}
Jet Divide(const Jet& a, const Jet& b) {
  Jet q;
  for (int k = 0; k < 4; ++k) {
    double s = a.c[k];
    for (int j = 1; j <= k; ++j) s -= b.c[j] * q.c[k - j];
    q.c[k] = s / b.c[0];
  }
  return q;
}
/// d/dt as a jet (its top coefficient is unknown and left 0: valid to second order).
Jet Derivative(const Jet& f) { return Jet{{f.c[1], 2 * f.c[2], 3 * f.c[3], 0.0}}; }
void SinCos(const Jet& f, Jet* s, Jet* c) {
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
Jet Compose(const std::array<double, 4>& g, const Jet& u) {
  Jet d = u;
  d.c[0] = 0.0;
  const Jet d2 = d * d, d3 = d2 * d;
  return Jet::Constant(g[0]) + g[1] * d + (0.5 * g[2]) * d2 + (g[3] / 6.0) * d3;
}
/// A sin(w t + phase) as a jet at t.
Jet Sinusoid(double amplitude, double w, double phase, double t) {
  const double s = std::sin(w * t + phase), c = std::cos(w * t + phase);
  return Jet::FromDerivatives(amplitude * s, amplitude * w * c, -amplitude * w * w * s, -amplitude * w * w * w * c);
}

/// Kinematics of R_world_base = Rz(yaw) Ry(pitch) Rx(roll) at position p: body rates from the ZYX Euler rates.
BaseKinematics KinematicsFromJets(const std::array<Jet, 3>& p, const Jet& yaw, const Jet& pitch, const Jet& roll) {
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

double WrapPi(double a) { return std::remainder(a, 2.0 * M_PI); }

// ---- Waypoint plans (handheld, wheeled). ----

/// A walk/drive through waypoints at constant speed with exact rests, as smoothed jump series: position
/// (order 1, velocity jumps), heading (order 0), and the gait envelope (order 0, 1 while moving).
struct WaypointPlan {
  std::unique_ptr<SmoothedPlan> position, heading, moving;
  double duration_s = 0.0;
};

std::vector<Waypoint2d> StopSequence(const std::vector<Waypoint2d>& w, bool closed_loop, int laps) {
  std::vector<Waypoint2d> seq{w.front()};
  for (int lap = 0; lap < (closed_loop ? laps : 1); ++lap) {
    seq.insert(seq.end(), w.begin() + 1, w.end());
    if (closed_loop) seq.push_back(w.front());
  }
  return seq;
}

WaypointPlan BuildWaypointPlan(const std::vector<Waypoint2d>& waypoints, bool closed_loop, int laps,
                               double speed_mps, double width_s) {
  const std::vector<Waypoint2d> seq = StopSequence(waypoints, closed_loop, laps);
  auto leg = [&](size_t i) {  // unit direction of the leg from seq[i] to seq[i + 1]
    return Eigen::Vector3d(seq[i + 1].x_m - seq[i].x_m, seq[i + 1].y_m - seq[i].y_m, 0.0).normalized();
  };
  auto length = [&](size_t i) { return std::hypot(seq[i + 1].x_m - seq[i].x_m, seq[i + 1].y_m - seq[i].y_m); };
  auto heading = [&](size_t i) { return std::atan2(leg(i).y(), leg(i).x()); };
  const Eigen::Vector3d unit_x = Eigen::Vector3d::UnitX();
  std::vector<Jump> velocity, turns, gait;
  // A stop's plan rest is dwell + width: the kernel spends width/2 on each side, leaving an exact dwell_s rest.
  double t_dep = seq[0].dwell_s + 0.5 * width_s;
  velocity.push_back({t_dep, speed_mps * leg(0)});
  gait.push_back({t_dep, unit_x});
  WaypointPlan plan;
  for (size_t i = 1; i < seq.size(); ++i) {
    const double t_arr = t_dep + length(i - 1) / speed_mps;
    if (i + 1 == seq.size()) {
      velocity.push_back({t_arr, -speed_mps * leg(i - 1)});
      gait.push_back({t_arr, -unit_x});
      plan.duration_s = t_arr + 0.5 * width_s + seq[i].dwell_s;
      break;
    }
    const double turn = WrapPi(heading(i) - heading(i - 1));
    if (seq[i].dwell_s > 0) {
      t_dep = t_arr + seq[i].dwell_s + width_s;
      velocity.push_back({t_arr, -speed_mps * leg(i - 1)});
      gait.push_back({t_arr, -unit_x});
      turns.push_back({0.5 * (t_arr + t_dep), turn * unit_x});  // turn in place, centred in the rest
      velocity.push_back({t_dep, speed_mps * leg(i)});
      gait.push_back({t_dep, unit_x});
    } else {
      t_dep = t_arr;
      velocity.push_back({t_arr, speed_mps * (leg(i) - leg(i - 1))});
      turns.push_back({t_arr, turn * unit_x});
    }
  }
  const Eigen::Vector3d start(seq[0].x_m, seq[0].y_m, 0.0);
  plan.position = std::make_unique<SmoothedPlan>(1, width_s, start, std::move(velocity));
  plan.heading = std::make_unique<SmoothedPlan>(0, width_s, heading(0) * unit_x, std::move(turns));
  plan.moving = std::make_unique<SmoothedPlan>(0, width_s, Eigen::Vector3d::Zero(), std::move(gait));
  return plan;
}

class HandheldWalk final : public BaseMotion {
 public:
  explicit HandheldWalk(const HandheldWalkConfig& c)
      : c_(c), plan_(BuildWaypointPlan(c.waypoints, c.closed_loop, c.laps, c.speed_mps, c.smoothing_s)) {}
  Seconds Duration() const override { return plan_.duration_s; }
  BaseKinematics At(Seconds t) const override {
    const std::array<Jet, 3> p = plan_.position->Eval(t);
    const Jet yaw = plan_.heading->Eval(t)[0], moving = plan_.moving->Eval(t)[0];
    const double w_step = 2.0 * M_PI * c_.step_hz;
    const Jet step = moving * Sinusoid(1.0, w_step, 0.0, t);        // vertical bounce, once per step
    const Jet stride = moving * Sinusoid(1.0, 0.5 * w_step, 0.0, t);  // side to side, once per stride
    const Jet nod = moving * Sinusoid(1.0, w_step, 0.5 * M_PI, t);
    Jet sin_yaw, cos_yaw;
    SinCos(yaw, &sin_yaw, &cos_yaw);
    const Jet lateral = c_.sway_amplitude_m * stride;  // along base +y
    const std::array<Jet, 3> position = {p[0] - lateral * sin_yaw, p[1] + lateral * cos_yaw,
                                         Jet::Constant(c_.height_m) + c_.bounce_amplitude_m * step};
    return KinematicsFromJets(position, yaw, c_.pitch_amplitude_rad * nod, c_.roll_amplitude_rad * stride);
  }

 private:
  HandheldWalkConfig c_;
  WaypointPlan plan_;
};

class WheeledPath final : public BaseMotion {
 public:
  explicit WheeledPath(const WheeledConfig& c)
      : height_m_(c.height_m),
        plan_(BuildWaypointPlan(c.waypoints, c.closed_loop, c.laps, c.speed_mps, c.smoothing_s)) {}
  Seconds Duration() const override { return plan_.duration_s; }
  BaseKinematics At(Seconds t) const override {
    const std::array<Jet, 3> p = plan_.position->Eval(t);
    return KinematicsFromJets({p[0], p[1], Jet::Constant(height_m_)}, plan_.heading->Eval(t)[0], Jet(), Jet());
  }

 private:
  double height_m_;
  WaypointPlan plan_;
};

// ---- Car: spline path, curvature-limited speed profile. ----

class CarPath final : public BaseMotion {
 public:
  CarPath(double height_m, CubicSpline path, std::unique_ptr<SmoothedPlan> u_of_t, double duration_s)
      : height_m_(height_m), path_(std::move(path)), u_of_t_(std::move(u_of_t)), duration_s_(duration_s) {}
  Seconds Duration() const override { return duration_s_; }
  BaseKinematics At(Seconds t) const override {
    const Jet u = u_of_t_->Eval(t)[0];
    const Eigen::MatrixX4d g = path_.Eval(u.c[0]);
    auto derivs = [&](int dim, int first) {
      std::array<double, 4> d{};
      for (int j = first; j < 4; ++j) d[size_t(j - first)] = g(dim, j);
      return d;
    };
    const Jet yaw = Atan2(Compose(derivs(1, 1), u), Compose(derivs(0, 1), u));  // along the tangent
    return KinematicsFromJets({Compose(derivs(0, 0), u), Compose(derivs(1, 0), u), Jet::Constant(height_m_)}, yaw,
                              Jet(), Jet());
  }

 private:
  double height_m_;
  CubicSpline path_;
  std::unique_ptr<SmoothedPlan> u_of_t_;
  double duration_s_;
};

/// Speed limit [m/s] at samples u_i: the file's speed (or cruise), the lateral-acceleration limit, and a
/// minimum over +-reach_m (the smoothed speed at a point averages the plan over half a kernel width around it).
std::vector<double> SpeedLimits(const CarConfig& c, const std::vector<CarWaypoint>& points,
                                const std::vector<double>& knots, const CubicSpline& path,
                                const std::vector<double>& u) {
  std::vector<double> raw(u.size());
  double fastest = 0.0;
  for (size_t i = 0; i < u.size(); ++i) {
    const size_t k = std::min(size_t(std::upper_bound(knots.begin(), knots.end(), u[i]) - knots.begin()),
                              knots.size() - 1);
    auto speed = [&](size_t j) { return points[j].speed_mps > 0 ? points[j].speed_mps : c.cruise_speed_mps; };
    const double s = std::clamp((u[i] - knots[k - 1]) / (knots[k] - knots[k - 1]), 0.0, 1.0);
    const Eigen::MatrixX4d g = path.Eval(u[i]);
    const double norm = std::hypot(g(0, 1), g(1, 1));
    const double curvature = std::abs(g(0, 1) * g(1, 2) - g(1, 1) * g(0, 2)) / (norm * norm * norm);
    raw[i] = std::min((1 - s) * speed(k - 1) + s * speed(k),
                      std::sqrt(c.max_lateral_accel_mps2 / std::max(curvature, 1e-12)));
    fastest = std::max(fastest, raw[i]);
  }
  const double reach_m = fastest * c.smoothing_s;  // the plan and the smoothed position differ by < half of it
  std::vector<double> limit(u.size());
  for (size_t i = 0, lo = 0; i < u.size(); ++i) {
    while (u[lo] < u[i] - reach_m) ++lo;
    limit[i] = raw[i];
    for (size_t j = lo; j < u.size() && u[j] <= u[i] + reach_m; ++j) limit[i] = std::min(limit[i], raw[j]);
  }
  return limit;
}

}  // namespace

Pose3 KittiPoseToWorldBase(const KittiPathConfig& c, const Pose3& T_cam0start_cam0k) {
  Pose3 T_cam_base = Pose3::Identity();  // base x = cam z, base y = -cam x, base z = -cam y
  T_cam_base.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  const Pose3 T_world_start = Eigen::Translation3d(c.start_x_m, c.start_y_m, c.height_m) * RotZ(c.start_yaw_rad);
  return T_world_start * T_cam_base.inverse() * T_cam0start_cam0k * T_cam_base;
}

namespace {

class KittiPath final : public BaseMotion {
 public:
  KittiPath(CubicSpline pose_of_t, double duration_s) : spline_(std::move(pose_of_t)), duration_s_(duration_s) {}
  Seconds Duration() const override { return duration_s_; }
  BaseKinematics At(Seconds t) const override {
    const Eigen::MatrixX4d g = spline_.Eval(t);  // rows x, y, z, yaw, pitch, roll
    Jet j[6];
    for (int d = 0; d < 6; ++d) j[d] = Jet::FromDerivatives(g(d, 0), g(d, 1), g(d, 2), g(d, 3));
    return KinematicsFromJets({j[0], j[1], j[2]}, j[3], j[4], j[5]);
  }

 private:
  CubicSpline spline_;
  double duration_s_;
};

/// Gaussian-weighted moving average of the rows over time (sigma_s), the window symmetric about each frame and
/// shrunk near the ends so that a uniformly moving sample stays put and the end frames are exact.
Eigen::MatrixXd SmoothFrames(const std::vector<double>& t, const Eigen::MatrixXd& values, double sigma_s) {
  const long n = values.rows();
  Eigen::MatrixXd out(n, values.cols());
  for (long k = 0; k < n; ++k) {
    Eigen::RowVectorXd sum = values.row(k);
    double weight = 1.0;
    for (long r = 1; r <= std::min(k, n - 1 - k); ++r) {
      const double dt = 0.5 * (t[size_t(k + r)] - t[size_t(k - r)]);
      if (dt > 3.0 * sigma_s) break;
      const double w = std::exp(-0.5 * dt * dt / (sigma_s * sigma_s));
      sum += w * (values.row(k - r) + values.row(k + r));
      weight += 2.0 * w;
    }
    out.row(k) = sum / weight;
  }
  return out;
}

}  // namespace

std::unique_ptr<BaseMotion> MakeHandheldWalk(const HandheldWalkConfig& config) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  return std::make_unique<HandheldWalk>(config);
}

std::unique_ptr<BaseMotion> MakeWheeledPath(const WheeledConfig& config) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  return std::make_unique<WheeledPath>(config);
}

Status MakeCarPath(const CarConfig& c, const std::vector<CarWaypoint>& points, std::unique_ptr<BaseMotion>* motion) {
  std::string error;
  if (!c.Validate(&error)) return Status::Error(error);
  if (points.size() < 2) return Status::Error(c.waypoints_file + ": need at least 2 waypoints");
  std::vector<double> knots{0.0};
  Eigen::MatrixXd xy(long(points.size()), 2);
  for (size_t i = 0; i < points.size(); ++i) {
    xy.row(long(i)) << points[i].x_m, points[i].y_m;
    if (i == 0) continue;
    const double chord = std::hypot(points[i].x_m - points[i - 1].x_m, points[i].y_m - points[i - 1].y_m);
    if (!(chord >= 0.01))
      return Status::Error(c.waypoints_file + ":" + std::to_string(points[i].line) +
                           ": waypoint repeats the previous one (closer than 0.01 m)");
    knots.push_back(knots.back() + chord);
  }
  CubicSpline path(knots, xy);
  const double length = knots.back();
  const size_t n = std::max<size_t>(41, size_t(std::ceil(length / 0.5)) + 1);
  std::vector<double> u(n), stretch(n);  // stretch = |dC/du| (~1 for a chord-length parameter)
  for (size_t i = 0; i < n; ++i) {
    u[i] = length * double(i) / double(n - 1);
    const Eigen::MatrixX4d g = path.Eval(u[i]);
    stretch[i] = std::hypot(g(0, 1), g(1, 1));
    if (!(stretch[i] > 0.05))
      return Status::Error(c.waypoints_file + ": the spline through the waypoints folds back near u = " +
                           std::to_string(u[i]) + " m (waypoints too irregular)");
  }
  std::vector<double> v = SpeedLimits(c, points, knots, path, u);
  v.front() = v.back() = 0.0;
  const double du = u[1] - u[0];
  for (size_t i = 0; i + 1 < n; ++i)  // accelerate within max_accel
    v[i + 1] = std::min(v[i + 1], std::sqrt(v[i] * v[i] + 2 * c.max_accel_mps2 * du * stretch[i]));
  for (size_t i = n - 1; i > 0; --i)  // brake within max_decel
    v[i - 1] = std::min(v[i - 1], std::sqrt(v[i] * v[i] + 2 * c.max_decel_mps2 * du * stretch[i]));
  // Plan in u: rates q_i = v_i / stretch_i, constant u-acceleration between samples, starting at t = w/2.
  std::vector<Jump> jumps;
  double t = 0.5 * c.smoothing_s, a_prev = 0.0;
  for (size_t i = 0; i + 1 < n; ++i) {
    const double q0 = v[i] / stretch[i], q1 = v[i + 1] / stretch[i + 1];
    const double dt = 2.0 * du / (q0 + q1);
    const double a = (q1 - q0) / dt;
    jumps.push_back({t, Eigen::Vector3d(a - a_prev, 0, 0)});
    a_prev = a;
    t += dt;
  }
  jumps.push_back({t, Eigen::Vector3d(-a_prev, 0, 0)});
  auto u_of_t = std::make_unique<SmoothedPlan>(2, c.smoothing_s, Eigen::Vector3d::Zero(), std::move(jumps));
  *motion = std::make_unique<CarPath>(c.height_m, std::move(path), std::move(u_of_t), t + 0.5 * c.smoothing_s);
  return Status::Ok();
}

Status MakeKittiPath(const KittiPathConfig& c, const std::vector<Pose3>& T_cam0start_cam0k,
                     const std::vector<double>& times_s, std::unique_ptr<BaseMotion>* motion) {
  std::string error;
  if (!c.Validate(&error)) return Status::Error(error);
  const size_t n = T_cam0start_cam0k.size();
  if (n < 2) return Status::Error(c.poses_file + ": need at least 2 poses");
  if (!times_s.empty() && times_s.size() != n)
    return Status::Error(c.times_file + ": " + std::to_string(times_s.size()) + " times for " + std::to_string(n) +
                         " poses in " + c.poses_file);
  std::vector<double> t(n);
  Eigen::MatrixXd values(long(n), 6);
  for (size_t k = 0; k < n; ++k) {
    t[k] = times_s.empty() ? double(k) / c.rate_hz : times_s[k] - times_s[0];
    if (k > 0 && !(t[k] > t[k - 1])) return Status::Error(c.times_file + ": times must increase strictly");
    const Pose3 T = KittiPoseToWorldBase(c, T_cam0start_cam0k[k]);
    const Eigen::Matrix3d& R = T.linear();
    const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
    if (std::abs(pitch) > 1.2)
      return Status::Error(c.poses_file + ":" + std::to_string(k + 1) + ": pitch " + std::to_string(pitch) +
                           " rad is too steep for the ZYX-Euler interpolation (|pitch| <= 1.2 rad)");
    double yaw = std::atan2(R(1, 0), R(0, 0)), roll = std::atan2(R(2, 1), R(2, 2));
    if (k > 0) {  // unwrap: the spline must not see 2 pi jumps
      yaw = values(long(k - 1), 3) + WrapPi(yaw - values(long(k - 1), 3));
      roll = values(long(k - 1), 5) + WrapPi(roll - values(long(k - 1), 5));
    }
    values.row(long(k)) << T.translation().transpose(), yaw, pitch, roll;
  }
  if (c.smoothing_s > 0) values = SmoothFrames(t, values, c.smoothing_s);
  *motion = std::make_unique<KittiPath>(CubicSpline(t, values), t.back());
  return Status::Ok();
}

Status MakeCarrierMotion(const CarrierConfig& config, std::unique_ptr<BaseMotion>* motion) {
  std::string error;
  if (!config.Validate(&error)) return Status::Error("carrier: " + error);
  switch (config.type) {
    case CarrierType::kScriptedLoop:
      *motion = std::make_unique<ScriptedBaseMotion>(config.scripted_loop);
      return Status::Ok();
    case CarrierType::kHandheld:
      *motion = MakeHandheldWalk(config.handheld);
      return Status::Ok();
    case CarrierType::kWheeled:
      *motion = MakeWheeledPath(config.wheeled);
      return Status::Ok();
    case CarrierType::kCar: {
      std::vector<CarWaypoint> points;
      if (Status s = LoadCarWaypointsCsv(config.car.waypoints_file, &points); !s) return s;
      return MakeCarPath(config.car, points, motion);
    }
    case CarrierType::kKitti: {
      std::vector<Pose3> poses;
      std::vector<double> times;
      if (Status s = LoadKittiPoses(config.kitti.poses_file, &poses); !s) return s;
      if (!config.kitti.times_file.empty())
        if (Status s = LoadKittiTimes(config.kitti.times_file, &times); !s) return s;
      return MakeKittiPath(config.kitti, poses, times, motion);
    }
  }
  return Status::Error("carrier: unknown type");
}

}  // namespace rotolidar::sim
