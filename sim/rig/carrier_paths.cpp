#include "sim/rig/carrier_paths.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "sim/rig/path_math.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

using namespace path_math;  // NOLINT: the paths are written in the jets' arithmetic


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
      if (!config.car.waypoints_file.empty()) {
        if (Status s = LoadCarWaypointsCsv(config.car.waypoints_file, &points); !s) return s;
      } else {
        for (size_t i = 0; i < config.car.waypoints.size(); ++i)
          points.push_back({config.car.waypoints[i].x_m, config.car.waypoints[i].y_m, 0.0, int(i) + 1});
      }
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
