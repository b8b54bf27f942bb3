#include "core/deskew/deskew.hpp"
#include "core/util/log.hpp"

#include <algorithm>
#include <cmath>

namespace rotolidar {

// Strapdown integration in the imu frame at t0: R, p, v of the imu frame at t relative to t0, gravity and the
// start velocity in the t0 frame. Midpoint rule as in core/imu/preintegration.cpp.
Status ImuMotionTable(const std::vector<ImuSample>& imu, Seconds t0_s, Seconds t1_s, const ImuMotionModel& model,
                      const Pose3& T_base_imu, MotionTable* out) {
  if (!(t1_s >= t0_s)) return Status::Error("ImuMotionTable: t1_s < t0_s");
  if (imu.empty() || imu.front().t_s > t0_s || imu.back().t_s < t1_s)
    return Status::Error("ImuMotionTable: IMU samples do not bracket [" + std::to_string(t0_s) + ", " +
                         std::to_string(t1_s) + "] s");
  const Pose3 T_imu_base = T_base_imu.inverse();
  MotionTable table;
  auto push = [&](Seconds t, const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
    Pose3 T_imu0_imu = Pose3::Identity();
    T_imu0_imu.linear() = R;
    T_imu0_imu.translation() = p;
    table.t_s.push_back(t);
    table.T_start_t.push_back(T_base_imu * T_imu0_imu * T_imu_base);
  };
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), v = model.v_imu_mps;
  push(t0_s, R, p);
  // First sample index whose interval [imu[i], imu[i+1]] reaches past t0.
  size_t i = size_t(std::upper_bound(imu.begin(), imu.end(), t0_s,
                                     [](Seconds t, const ImuSample& s) { return t < s.t_s; }) -
                    imu.begin());
  i = i > 0 ? i - 1 : 0;
  for (; i + 1 < imu.size() && imu[i].t_s < t1_s; ++i) {
    const double a = std::max(imu[i].t_s, t0_s), b = std::min(imu[i + 1].t_s, t1_s);
    const double dt = b - a;
    if (!(dt > 0)) continue;
    const Eigen::Vector3d w = 0.5 * (imu[i].gyro_radps + imu[i + 1].gyro_radps) - model.bias_gyro_radps;
    Eigen::Vector3d acc = Eigen::Vector3d::Zero();  // acceleration in the t0 frame
    if (model.use_accel) {
      const Eigen::Vector3d f = 0.5 * (imu[i].accel_mps2 + imu[i + 1].accel_mps2) - model.bias_accel_mps2;
      acc = R * ExpSO3(0.5 * dt * w) * f + model.gravity_imu_mps2;
    }
    p += v * dt + 0.5 * acc * dt * dt;
    v += acc * dt;
    R = R * ExpSO3(w * dt);
    push(b, R, p);
  }
  if (table.t_s.size() == 1) push(t1_s, R, p);  // t1 == t0
  *out = std::move(table);
  return Status::Ok();
}

MotionTable ConstantTwistTable(const Pose3& T_start_end, Seconds t0_s, Seconds t1_s, int steps) {
  ROTOLIDAR_CHECK(steps >= 1 && t1_s > t0_s, "ConstantTwistTable: need steps >= 1 and t1 > t0");
  const Eigen::Vector3d w = LogSO3(T_start_end.linear());
  MotionTable table;
  for (int k = 0; k <= steps; ++k) {
    const double s = double(k) / steps;
    Pose3 T = Pose3::Identity();
    T.linear() = ExpSO3(s * w);
    T.translation() = s * T_start_end.translation();
    table.t_s.push_back(t0_s + s * (t1_s - t0_s));
    table.T_start_t.push_back(T);
  }
  return table;
}

MotionTable IdentityTable(Seconds t0_s, Seconds t1_s) {
  MotionTable table;
  table.t_s = {t0_s};
  table.T_start_t = {Pose3::Identity()};
  if (t1_s > t0_s) {
    table.t_s.push_back(t1_s);
    table.T_start_t.push_back(Pose3::Identity());
  }
  return table;
}

Pose3 MotionTablePose(const MotionTable& table, Seconds t_s) {
  ROTOLIDAR_CHECK(!table.t_s.empty() && table.t_s.size() == table.T_start_t.size(),
                  "MotionTable: empty or mismatched sizes");
  bool outside = false;
  const size_t k = deskew_detail::Interval(table.t_s, t_s, 1, &outside);
  if (k == 0) return table.T_start_t.front();
  if (k >= table.t_s.size()) return table.T_start_t.back();
  const Pose3& a = table.T_start_t[k - 1];
  const Pose3& b = table.T_start_t[k];
  const double s = (t_s - table.t_s[k - 1]) / (table.t_s[k] - table.t_s[k - 1]);
  Pose3 out = Pose3::Identity();
  out.linear() = a.linear() * ExpSO3(s * LogSO3(a.linear().transpose() * b.linear()));
  out.translation() = (1.0 - s) * a.translation() + s * b.translation();
  return out;
}

MotionInterpolator::MotionInterpolator(const MotionTable& table) : table_(table) {
  ROTOLIDAR_CHECK(!table.t_s.empty() && table.t_s.size() == table.T_start_t.size(),
                  "MotionTable: empty or mismatched sizes");
  seg_.reserve(table.t_s.size());
  for (size_t k = 1; k < table.t_s.size(); ++k) {
    const Pose3& a = table.T_start_t[k - 1];
    const Pose3& b = table.T_start_t[k];
    seg_.push_back({a.linear(), LogSO3(a.linear().transpose() * b.linear()), a.translation(), b.translation(),
                    1.0 / (table.t_s[k] - table.t_s[k - 1])});
  }
}

DeskewCounts DeskewScan(const RotorAngleInterpolator& rotor, const MotionTable& table, const LidarScan& scan,
                        std::vector<ScanPoint>* out) {
  RotaryTransform rotary(rotor);
  MotionInterpolator motion(table);
  out->resize(scan.points.size());
  DeskewCounts counts;
  for (size_t i = 0; i < scan.points.size(); ++i) {
    const LidarPoint& lp = scan.points[i];
    bool fell_back = false, outside = false;
    const Eigen::Vector3d p_base = rotary.Apply(lp, &fell_back);  // in the base frame at its own time
    (*out)[i] = ToScanPoint(lp, motion.Apply(lp.t_s, p_base, &outside));
    counts.rotor_fallback += fell_back ? 1 : 0;
    counts.motion_extrapolated += outside ? 1 : 0;
  }
  return counts;
}

}  // namespace rotolidar
