#include "sim/rig/carrier_paths.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "core/io/yaml_util.hpp"

namespace rotolidar::sim {
namespace {

std::string WriteFile(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "carrier_test_" + name;
  std::ofstream(path) << text;
  return path;
}

/// Maxima over a fine time grid, comparing the analytic derivatives with finite differences of the poses.
struct Smoothness {
  double v_err = 0, a_err = 0, omega_err = 0, alpha_err = 0;  ///< analytic vs central differences
  double max_speed = 0, max_accel = 0, max_jerk = 0;          ///< jerk = central difference of the analytic a
  double max_omega = 0, max_alpha = 0, max_alpha_rate = 0;
};

Smoothness Measure(const BaseMotion& m, double t0, double t1, double dt) {
  Smoothness s;
  const double h = 1e-4;  // for v, a, omega, alpha checks
  for (double t = t0; t <= t1; t += dt) {
    const BaseKinematics k = m.At(t), kp = m.At(t + h), km = m.At(t - h);
    const Eigen::Vector3d p = k.T_world_base.translation();
    const Eigen::Vector3d v_fd = (kp.T_world_base.translation() - km.T_world_base.translation()) / (2 * h);
    const Eigen::Vector3d a_fd = (kp.v_world_mps - km.v_world_mps) / (2 * h);
    const Eigen::Matrix3d& R = k.T_world_base.linear();
    const Eigen::Vector3d w_fd =
        LogSO3(km.T_world_base.linear().transpose() * kp.T_world_base.linear()) / (2 * h);
    const Eigen::Vector3d alpha_fd = (kp.omega_base_radps - km.omega_base_radps) / (2 * h);
    s.v_err = std::max(s.v_err, (v_fd - k.v_world_mps).norm());
    s.a_err = std::max(s.a_err, (a_fd - k.a_world_mps2).norm());
    s.omega_err = std::max(s.omega_err, (w_fd - k.omega_base_radps).norm());
    s.alpha_err = std::max(s.alpha_err, (alpha_fd - k.alpha_base_radps2).norm());
    s.max_speed = std::max(s.max_speed, k.v_world_mps.norm());
    s.max_accel = std::max(s.max_accel, k.a_world_mps2.norm());
    s.max_jerk = std::max(s.max_jerk, (kp.a_world_mps2 - km.a_world_mps2).norm() / (2 * h));
    s.max_omega = std::max(s.max_omega, k.omega_base_radps.norm());
    s.max_alpha = std::max(s.max_alpha, k.alpha_base_radps2.norm());
    s.max_alpha_rate = std::max(s.max_alpha_rate, (kp.alpha_base_radps2 - km.alpha_base_radps2).norm() / (2 * h));
    EXPECT_TRUE(p.allFinite() && R.allFinite()) << "t " << t;
  }
  std::printf("err v %.2g a %.2g w %.2g alpha %.2g | max speed %.3g accel %.3g jerk %.3g omega %.3g alpha %.3g "
              "dalpha %.3g\n",
              s.v_err, s.a_err, s.omega_err, s.alpha_err, s.max_speed, s.max_accel, s.max_jerk, s.max_omega,
              s.max_alpha, s.max_alpha_rate);
  return s;
}

// Central differences with h = 1e-4 s are exact to h^2/6 * (next derivative): position -> v within
// 1e-8/6 * 50 m/s^3 (gait jerk) ~ 1e-7; v -> a within 1e-8/6 * 700 m/s^4 ~ 1e-6; round-off ~1e-16 * 10 m / h =
// 1e-11. Bounds 1e-5 (v, omega) and 1e-4 (a, alpha) leave room for the 2 Hz gait terms. Where the jerk (angular
// jerk) is only piecewise continuous (splines through data: it jumps at the knots), a difference straddling a
// knot adds up to h * |jump| / 2 <= h * max: pass jerk_jumps to allow that.
void ExpectConsistentDerivatives(const Smoothness& s, bool jerk_jumps = false) {
  const double h = 1e-4;
  EXPECT_LT(s.v_err, 1e-5);
  EXPECT_LT(s.a_err, 1e-4 + (jerk_jumps ? h * s.max_jerk : 0.0));
  EXPECT_LT(s.omega_err, 1e-5);
  EXPECT_LT(s.alpha_err, 1e-4 + (jerk_jumps ? h * s.max_alpha_rate : 0.0));
}

HandheldWalkConfig RoomWalk() {
  HandheldWalkConfig c;
  c.waypoints = {{0, 0, 0}, {6, 0, 3.0}, {6, 4, 0}, {0, 4, 0}};
  c.closed_loop = true;
  return c;
}

// Analytic bounds for the defaults (speed 1.2, smoothing 2 s => kernel knot spacing h = 0.5 s, max K = 1.33/s,
// max |K'| = 2.67/s^2): plan acceleration <= |dv| max K = 1.7 * 1.33 = 2.3 m/s^2 at a 90 deg corner, plan jerk
// <= 1.7 * 2.67 = 4.5 m/s^3; bounce adds A (2 pi f)^2 = 3.2 m/s^2 and A (2 pi f)^3 = 40 m/s^3, sway 0.8 and 5,
// the fading of the gait a few more. Bounds: 7 m/s^2, 70 m/s^3. Speed <= 1.2 + sway (0.02 * 2 pi = 0.13) +
// fade/turn terms (< 0.07) -> 1.4 m/s, the top of the walking envelope.
TEST(HandheldWalk, SmoothAtWalkingSpeedAndHandHeight) {
  const HandheldWalkConfig c = RoomWalk();
  const auto walk = MakeHandheldWalk(c);
  std::printf("duration %.2f s\n", walk->Duration());
  const Smoothness s = Measure(*walk, 0.0, walk->Duration() + 1.0, 0.011);
  ExpectConsistentDerivatives(s);
  EXPECT_LT(s.max_speed, 1.4);
  EXPECT_LT(s.max_accel, 7.0);
  EXPECT_LT(s.max_jerk, 70.0);
  EXPECT_LT(s.max_omega, 3.0);
  double straight_speed_sum = 0;
  int straight = 0;
  for (double t = 0; t < walk->Duration(); t += 0.01) {
    const BaseKinematics k = walk->At(t);
    EXPECT_NEAR(k.T_world_base.translation().z(), c.height_m, c.bounce_amplitude_m + 1e-12);
    const Eigen::Vector3d x_axis = k.T_world_base.linear().col(0);
    EXPECT_LT(std::abs(x_axis.z()), std::sin(c.pitch_amplitude_rad) + 1e-12);  // only the small nod
    const Eigen::Vector2d v = k.v_world_mps.head<2>();
    if (v.norm() > 0.9) {  // heading along the path (sway and corner rounding: a few degrees)
      EXPECT_GT(x_axis.head<2>().normalized().dot(v.normalized()), std::cos(15.0 * M_PI / 180)) << "t " << t;
      straight_speed_sum += v.norm(), ++straight;
    }
  }
  ASSERT_GT(straight, 1000);
  EXPECT_NEAR(straight_speed_sum / straight, c.speed_mps, 0.1);
}

// The 3 s dwell at (6, 0) is an exact translational rest of 3 s (the kernel's half widths sit before and after
// it), during which the walker turns 90 deg in place; the start and end are at rest at the first waypoint.
TEST(HandheldWalk, DwellReallyPausesAndEndsAtRest) {
  const HandheldWalkConfig c = RoomWalk();
  const auto walk = MakeHandheldWalk(c);
  const double dt = 0.001;
  double rest = 0, first_rest = -1, yaw_before = 0, yaw_after = 0;
  for (double t = 0.5; t < walk->Duration() - 1.0; t += dt) {
    const BaseKinematics k = walk->At(t);
    const bool at_rest = k.v_world_mps.norm() < 1e-12 &&
                         (k.T_world_base.translation() - Eigen::Vector3d(6, 0, c.height_m)).norm() < 1e-9;
    if (at_rest) {
      if (first_rest < 0) first_rest = t, yaw_before = std::atan2(k.T_world_base(1, 0), k.T_world_base(0, 0));
      rest += dt;
      yaw_after = std::atan2(k.T_world_base(1, 0), k.T_world_base(0, 0));
    }
  }
  std::printf("rest %.3f s from t = %.3f, yaw %.4f -> %.4f\n", rest, first_rest, yaw_before, yaw_after);
  EXPECT_NEAR(rest, 3.0, 2 * dt);
  EXPECT_NEAR(yaw_before, 0.0, 1e-9);
  EXPECT_NEAR(yaw_after, M_PI / 2, 1e-9);
  for (double t : {0.0, walk->Duration(), walk->Duration() + 7.0}) {
    const BaseKinematics k = walk->At(t);
    EXPECT_LT((k.T_world_base.translation() - Eigen::Vector3d(0, 0, c.height_m)).norm(), 1e-9) << t;
    EXPECT_LT(k.v_world_mps.norm() + k.a_world_mps2.norm() + k.omega_base_radps.norm(), 1e-9) << t;
  }
  EXPECT_GT(walk->At(0.6).v_world_mps.norm(), 0.05);  // no start dwell: walks off at once, smoothly
}

// Gait: on a straight leg the bounce spans 2 * amplitude over a step; the amplitude is set by the config.
TEST(HandheldWalk, GaitBounceAtStepFrequency) {
  HandheldWalkConfig c;
  c.waypoints = {{0, 0, 0}, {30, 0, 0}};
  c.bounce_amplitude_m = 0.03;
  const auto walk = MakeHandheldWalk(c);
  double zmin = 1e9, zmax = -1e9, ymin = 1e9, ymax = -1e9;
  for (double t = 10.0; t < 11.0; t += 0.001) {  // mid-leg: full gait
    const Eigen::Vector3d p = walk->At(t).T_world_base.translation();
    zmin = std::min(zmin, p.z()), zmax = std::max(zmax, p.z());
    ymin = std::min(ymin, p.y()), ymax = std::max(ymax, p.y());
  }
  EXPECT_NEAR(zmax - zmin, 2 * c.bounce_amplitude_m, 1e-4);
  EXPECT_NEAR(ymax - ymin, 2 * c.sway_amplitude_m, 1e-4);  // one stride = one full sway cycle at 1 Hz
  EXPECT_NEAR(walk->At(walk->Duration()).T_world_base.translation().x(), 30.0, 1e-9);
}

TEST(WheeledPath, FlatAtMountHeightWithinSpeedAndAcceleration) {
  WheeledConfig c;
  c.waypoints = {{0, 0, 0}, {5, 0, 0}, {5, 5, 2.0}, {-2, 3, 0}};
  const auto robot = MakeWheeledPath(c);
  const Smoothness s = Measure(*robot, 0.0, robot->Duration() + 1.0, 0.013);
  ExpectConsistentDerivatives(s);
  // Smoothing 3 s: knot spacing h = 0.75 s, max K = (2/3) / h = 0.89 /s, max |K'| = (2/3) / h^2 = 1.19 /s^2. The
  // legs are longer than the kernel, so one velocity jump acts at a time, at most 2 * speed = 1.6 m/s (a
  // reversal): |a| <= 1.6 * 0.89 = 1.42 m/s^2, |jerk| <= 1.6 * 1.19 = 1.9 m/s^3.
  EXPECT_LE(s.max_speed, c.speed_mps + 1e-12);
  EXPECT_LT(s.max_accel, 1.43);
  EXPECT_LT(s.max_jerk, 1.9);
  for (double t = 0; t < robot->Duration(); t += 0.05) {
    const BaseKinematics k = robot->At(t);
    EXPECT_EQ(k.T_world_base.translation().z(), c.height_m);
    EXPECT_NEAR(k.T_world_base.linear()(2, 2), 1.0, 1e-15);  // z axis up: no roll, no pitch
    EXPECT_EQ(k.omega_base_radps.x(), 0.0);
    EXPECT_EQ(k.omega_base_radps.y(), 0.0);
    EXPECT_EQ(k.v_world_mps.z(), 0.0);
  }
  EXPECT_LT((robot->At(robot->Duration()).T_world_base.translation().head<2>() - Eigen::Vector2d(-2, 3)).norm(),
            1e-9);
}

// A car on a 100 m straight, a 90 deg curve of radius 20 m (points every ~4 m) and another straight.
std::string CarCsv() {
  std::string csv = "# x_m,y_m,speed_mps\nx_m,y_m,speed_mps\n";
  for (int i = 0; i <= 20; ++i) csv += std::to_string(5.0 * i) + ",0\n";
  for (int i = 1; i < 8; ++i) {
    const double a = i * M_PI / 16;
    csv += std::to_string(100 + 20 * std::sin(a)) + "," + std::to_string(20 - 20 * std::cos(a)) + "\n";
  }
  for (int i = 0; i <= 20; ++i) csv += "120," + std::to_string(20.0 + 5.0 * i) + (i > 10 ? ",5\n" : "\n");
  return csv;
}

// Lateral acceleration |v x a| / |v| stays under max_lateral_accel (the speed cap is eroded over the kernel's
// reach, so smoothing cannot push the car into the curve too fast), and the longitudinal one under max_accel /
// max_decel (the smoothed acceleration is an average of the plan's); 5 % for the u-vs-arc-length approximation.
TEST(CarPath, SplineSpeedProfileRespectsLimits) {
  CarConfig c;
  c.waypoints_file = WriteFile("car.csv", CarCsv());
  c.cruise_speed_mps = 12.0;
  std::vector<CarWaypoint> points;
  ASSERT_TRUE(LoadCarWaypointsCsv(c.waypoints_file, &points).ok);
  std::unique_ptr<BaseMotion> car;
  const Status st = MakeCarPath(c, points, &car);
  ASSERT_TRUE(st.ok) << st.message;
  std::printf("car duration %.2f s\n", car->Duration());
  const Smoothness s = Measure(*car, 0.0, car->Duration() + 1.0, 0.01);
  ExpectConsistentDerivatives(s);
  EXPECT_LE(s.max_speed, c.cruise_speed_mps + 1e-6);
  double max_lateral = 0, max_accel = 0, max_brake = 0;
  for (double t = 0; t < car->Duration(); t += 0.01) {
    const BaseKinematics k = car->At(t);
    const double v = k.v_world_mps.norm();
    if (v > 0.5) {
      max_lateral = std::max(max_lateral, k.v_world_mps.cross(k.a_world_mps2).norm() / v);
      max_accel = std::max(max_accel, k.v_world_mps.dot(k.a_world_mps2) / v);
      max_brake = std::max(max_brake, -k.v_world_mps.dot(k.a_world_mps2) / v);
      const Eigen::Vector3d x_axis = k.T_world_base.linear().col(0);
      EXPECT_GT(x_axis.dot(k.v_world_mps / v), 1.0 - 1e-9);  // heading = tangent
    }
    EXPECT_EQ(k.T_world_base.translation().z(), c.height_m);
    EXPECT_NEAR(k.T_world_base.linear()(2, 2), 1.0, 1e-15);
    if (k.T_world_base.translation().y() > 80) {
      EXPECT_LT(v, 5.0 + 1e-6);  // the file's last points ask for 5 m/s
    }
  }
  std::printf("max lateral %.3f, acceleration %.3f, braking %.3f m/s^2\n", max_lateral, max_accel, max_brake);
  EXPECT_LT(max_lateral, 1.05 * c.max_lateral_accel_mps2);
  EXPECT_LT(max_accel, 1.05 * c.max_accel_mps2);
  EXPECT_LT(max_brake, 1.05 * c.max_decel_mps2);
  // Rest at both ends, through the first and last points.
  for (double t : {0.0, car->Duration()}) {
    EXPECT_LT(car->At(t).v_world_mps.norm(), 1e-9);
  }
  EXPECT_LT((car->At(0).T_world_base.translation().head<2>() - Eigen::Vector2d(0, 0)).norm(), 1e-9);
  EXPECT_LT((car->At(car->Duration()).T_world_base.translation().head<2>() - Eigen::Vector2d(120, 120)).norm(),
            1e-6);
}


// ---- KITTI ----

/// A smooth synthetic drive relative to its start (base frame at t = 0 = identity): a 30 m radius circle at
/// 6 m/s with a gentle grade, pitch and roll.
Pose3 DriveFromStart(double t) {
  const double w = 0.2, r = 30.0;
  Pose3 T = Pose3::Identity();
  T.translation() << r * std::sin(w * t), r * (1 - std::cos(w * t)), 0.5 * std::sin(0.2 * t);
  T.linear() = (Eigen::AngleAxisd(w * t, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(0.02 * std::sin(0.3 * t), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(0.01 * (std::cos(0.5 * t) - 1), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

/// The KITTI cam0 pose of a base pose relative to the start: P = T_cam_base T_start_base T_base_cam.
Pose3 ToKitti(const Pose3& T_start_base) {
  Pose3 T_cam_base = Pose3::Identity();
  T_cam_base.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  return T_cam_base * T_start_base * T_cam_base.inverse();
}

std::string KittiLines(const std::vector<double>& times) {
  std::ostringstream os;
  os.precision(17);
  for (double t : times) {
    const Pose3 P = ToKitti(DriveFromStart(t));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) os << P(r, c) << (r == 2 && c == 3 ? "\n" : " ");
  }
  return os.str();
}

double RotationError(const Pose3& a, const Pose3& b) { return LogSO3(a.linear().transpose() * b.linear()).norm(); }

TEST(KittiPath, CameraAxesBecomeAZUpBase) {
  KittiPathConfig c;
  c.height_m = 1.7;
  Pose3 P = Pose3::Identity();
  EXPECT_LT((KittiPoseToWorldBase(c, P).translation() - Eigen::Vector3d(0, 0, 1.7)).norm(), 1e-15);
  P.translation() << 1.0, -2.0, 5.0;  // 1 m right, 2 m up, 5 m forward in cam0
  EXPECT_LT((KittiPoseToWorldBase(c, P).translation() - Eigen::Vector3d(5, -1, 3.7)).norm(), 1e-12);
  P = Pose3::Identity();
  P.linear() = Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();  // turn left (about up)
  const Pose3 T = KittiPoseToWorldBase(c, P);
  EXPECT_LT(RotationError(T, Pose3(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()))), 1e-12);
  c.start_x_m = 10, c.start_y_m = -3, c.start_yaw_rad = M_PI / 2;
  P = Pose3::Identity();
  P.translation() << 0, 0, 5;  // forward = world +y after the start yaw
  EXPECT_LT((KittiPoseToWorldBase(c, P).translation() - Eigen::Vector3d(10, 2, 1.7)).norm(), 1e-12);
}

// Through every frame exactly (natural cubic splines interpolate), and between frames close to the true drive:
// at 10 Hz the interpolation error is ~ dt^4 |p''''| / 384 (~1e-7 m here); bounds 1e-3 m and 1e-4 rad, away
// from the first and last second where the natural end conditions bend the curve.
TEST(KittiPath, InterpolatesThroughEveryFrame) {
  std::vector<double> times;
  for (int k = 0; k < 200; ++k) times.push_back(0.1 * k);
  CarrierConfig config;
  config.type = CarrierType::kKitti;
  config.kitti.poses_file = WriteFile("kitti_poses.txt", KittiLines(times));
  config.kitti.height_m = 1.8;
  std::unique_ptr<BaseMotion> path;
  const Status st = MakeCarrierMotion(config, &path);
  ASSERT_TRUE(st.ok) << st.message;
  EXPECT_NEAR(path->Duration(), 19.9, 1e-12);
  const Pose3 lift(Eigen::Translation3d(0, 0, 1.8));
  for (double t : times) {
    const Pose3 expected = lift * DriveFromStart(t);
    const Pose3 got = path->At(t).T_world_base;
    ASSERT_LT((got.translation() - expected.translation()).norm(), 1e-9) << t;
    ASSERT_LT(RotationError(got, expected), 1e-9) << t;
  }
  double pos_err = 0, rot_err = 0, vel_err = 0;
  for (double t = 1.0; t < 18.9; t += 0.0123) {
    const Pose3 expected = lift * DriveFromStart(t);
    const BaseKinematics k = path->At(t);
    pos_err = std::max(pos_err, (k.T_world_base.translation() - expected.translation()).norm());
    rot_err = std::max(rot_err, RotationError(k.T_world_base, expected));
    const Eigen::Vector3d v_true =
        (DriveFromStart(t + 1e-5).translation() - DriveFromStart(t - 1e-5).translation()) / 2e-5;
    vel_err = std::max(vel_err, (k.v_world_mps - v_true).norm());
  }
  std::printf("between frames: position %.3g m, rotation %.3g rad, velocity %.3g m/s\n", pos_err, rot_err, vel_err);
  EXPECT_LT(pos_err, 1e-3);
  EXPECT_LT(rot_err, 1e-4);
  EXPECT_LT(vel_err, 0.01);
  ExpectConsistentDerivatives(Measure(*path, -1.0, 21.0, 0.017));  // incl. the straight extrapolations
}

// With a times file (non-uniform stamps), t = 0 is the first stamp and each frame sits at its own time.
TEST(KittiPath, UsesTheTimesFile) {
  std::vector<double> times;
  std::string times_txt;
  for (int k = 0; k < 60; ++k) {
    times.push_back(0.1 * k + 0.003 * std::sin(1.7 * k));
    times_txt += std::to_string(times.back() + 1000.0) + "\n";
  }
  KittiPathConfig c;
  c.poses_file = WriteFile("kitti_poses_t.txt", KittiLines(times));
  c.times_file = WriteFile("kitti_times.txt", times_txt);
  std::vector<Pose3> poses;
  std::vector<double> loaded;
  ASSERT_TRUE(LoadKittiPoses(c.poses_file, &poses).ok);
  ASSERT_TRUE(LoadKittiTimes(c.times_file, &loaded).ok);
  std::unique_ptr<BaseMotion> path;
  ASSERT_TRUE(MakeKittiPath(c, poses, loaded, &path).ok);
  for (size_t k = 0; k < poses.size(); ++k) {
    const Pose3 expected = KittiPoseToWorldBase(c, poses[k]);
    ASSERT_LT((path->At(loaded[k] - loaded[0]).T_world_base.translation() - expected.translation()).norm(), 1e-9);
  }
  EXPECT_NEAR(path->Duration(), loaded.back() - loaded.front(), 1e-12);
  loaded.pop_back();
  const Status st = MakeKittiPath(c, poses, loaded, &path);
  EXPECT_FALSE(st.ok);
  EXPECT_NE(st.message.find("59 times for 60 poses"), std::string::npos) << st.message;
}

// Real data (ROTOLIDAR_DATA): KITTI sequence 00 with its times file, 4541 frames over 470 s.
TEST(KittiPath, RealSequence00MatchesEveryFrame) {
  const char* data = std::getenv("ROTOLIDAR_DATA");
  if (!data) GTEST_SKIP() << "ROTOLIDAR_DATA is not set: skipping the KITTI 00 real-data check";
  CarrierConfig config;
  config.type = CarrierType::kKitti;
  config.kitti.poses_file = std::string(data) + "/kitti_poses/00.txt";
  config.kitti.times_file = std::string(data) + "/evo/KITTI_00_gt_times.txt";
  std::unique_ptr<BaseMotion> path;
  const Status st = MakeCarrierMotion(config, &path);
  ASSERT_TRUE(st.ok) << st.message;
  std::vector<Pose3> poses;
  std::vector<double> times;
  ASSERT_TRUE(LoadKittiPoses(config.kitti.poses_file, &poses).ok);
  ASSERT_TRUE(LoadKittiTimes(config.kitti.times_file, &times).ok);
  ASSERT_EQ(poses.size(), 4541u);
  double pos_err = 0, rot_err = 0, max_speed = 0;
  for (size_t k = 0; k < poses.size(); ++k) {
    const BaseKinematics got = path->At(times[k] - times[0]);
    const Pose3 expected = KittiPoseToWorldBase(config.kitti, poses[k]);
    pos_err = std::max(pos_err, (got.T_world_base.translation() - expected.translation()).norm());
    rot_err = std::max(rot_err, RotationError(got.T_world_base, expected));
    max_speed = std::max(max_speed, got.v_world_mps.norm());
  }
  std::printf("KITTI 00: %zu frames, %.1f s, max frame error %.3g m / %.3g rad, max speed %.2f m/s\n", poses.size(),
              path->Duration(), pos_err, rot_err, max_speed);
  EXPECT_LT(pos_err, 1e-9);
  EXPECT_LT(rot_err, 1e-9);
  EXPECT_LT(max_speed, 20.0);  // an urban drive
  EXPECT_NEAR(path->At(0).T_world_base.translation().z(), config.kitti.height_m, 1e-12);
  const Smoothness raw = Measure(*path, 0.0, path->Duration(), 0.0123);
  ExpectConsistentDerivatives(raw, true);
  // The raw ground truth jumps by up to ~1 m/s between frames (frame 2130: 5.24 -> 6.31 m/s) and its stamps
  // jitter by a few ms, so the exact interpolation reaches ~50 m/s^2 and ~850 m/s^3. Smoothing the frames
  // (sigma 0.2 s) gives a car-like path near the frames. Measured: max acceleration 7.1 m/s^2, frame deviation
  // median 1.8 cm, 99th percentile 8 cm, max 0.24 m (at the frame-2114 glitch); bounds about 2x above.
  config.kitti.smoothing_s = 0.2;
  ASSERT_TRUE(MakeCarrierMotion(config, &path).ok);
  const Smoothness smooth = Measure(*path, 0.0, path->Duration(), 0.0123);
  ExpectConsistentDerivatives(smooth, true);
  std::vector<double> deviation;
  for (size_t k = 0; k < poses.size(); ++k)
    deviation.push_back((path->At(times[k] - times[0]).T_world_base.translation() -
                         KittiPoseToWorldBase(config.kitti, poses[k]).translation())
                            .norm());
  std::sort(deviation.begin(), deviation.end());
  std::printf("smoothed (sigma 0.2 s): max acceleration %.2f (raw %.2f) m/s^2, jerk %.1f (raw %.1f) m/s^3, frame "
              "deviation median %.3f max %.3f m\n",
              smooth.max_accel, raw.max_accel, smooth.max_jerk, raw.max_jerk, deviation[deviation.size() / 2],
              deviation.back());
  EXPECT_LT(smooth.max_accel, 15.0);
  EXPECT_LT(deviation[deviation.size() / 2], 0.04);
  EXPECT_LT(deviation.back(), 0.5);
  EXPECT_EQ(deviation.front(), 0.0);  // the first frame stays exact
}

// ---- Files and config ----

std::string LoadCsvError(const std::string& name, const std::string& text) {
  std::vector<CarWaypoint> points{{1, 2, 3, 4}};
  const Status st = LoadCarWaypointsCsv(text.empty() ? name : WriteFile(name, text), &points);
  EXPECT_EQ(points.size(), 1u) << "a failed load must leave the output untouched";
  return st.ok ? "" : st.message;
}

TEST(PathFiles, BadFilesNameFileLineAndField) {
  std::string e = LoadCsvError("bad1.csv", "x_m,y_m\n0,0\n1.0,abc\n");
  EXPECT_NE(e.find("bad1.csv:3"), std::string::npos) << e;
  EXPECT_NE(e.find("y_m"), std::string::npos) << e;
  e = LoadCsvError("bad2.csv", "0,0\n\n# comment\n1,2,3,4\n");
  EXPECT_NE(e.find("bad2.csv:4"), std::string::npos) << e;
  e = LoadCsvError("bad3.csv", "0,0,1\n5,0,-2\n");
  EXPECT_NE(e.find("bad3.csv:2"), std::string::npos) << e;
  EXPECT_NE(e.find("speed_mps"), std::string::npos) << e;
  EXPECT_NE(LoadCsvError("bad4.csv", "0,0\n").find("at least 2"), std::string::npos);
  EXPECT_NE(LoadCsvError("/nonexistent/none.csv", "").find("cannot open"), std::string::npos);

  std::vector<Pose3> poses;
  Status st = LoadKittiPoses(WriteFile("bad_poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n"), &poses);
  EXPECT_NE(st.message.find("bad_poses.txt:2"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("12 numbers"), std::string::npos) << st.message;
  st = LoadKittiPoses(WriteFile("bad_rot.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0.2 0 0 0 1 0 0 0 0 1 0\n"), &poses);
  EXPECT_NE(st.message.find("bad_rot.txt:2"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("orthonormal"), std::string::npos) << st.message;
  st = LoadKittiPoses(WriteFile("bad_nan.txt", "1 0 0 0 0 1 0 0 0 0 1 nan\n"), &poses);
  EXPECT_NE(st.message.find("bad_nan.txt:1"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("field 12"), std::string::npos) << st.message;
  EXPECT_TRUE(poses.empty());
  std::vector<double> times;
  st = LoadKittiTimes(WriteFile("bad_times.txt", "0.0\n0.1\n0.1\n"), &times);
  EXPECT_NE(st.message.find("bad_times.txt:3"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("increase"), std::string::npos) << st.message;

  CarConfig car;
  car.waypoints_file = WriteFile("dup.csv", "0,0\n5,0\n5,0\n9,0\n");
  std::vector<CarWaypoint> points;
  ASSERT_TRUE(LoadCarWaypointsCsv(car.waypoints_file, &points).ok);
  std::unique_ptr<BaseMotion> motion;
  st = MakeCarPath(car, points, &motion);
  EXPECT_NE(st.message.find("dup.csv:3"), std::string::npos) << st.message;
  EXPECT_FALSE(motion);
}

TEST(CarrierConfig, DefaultIsTheScriptedLoopAndValidationNamesFields) {
  CarrierConfig c;
  std::unique_ptr<BaseMotion> motion;
  ASSERT_TRUE(MakeCarrierMotion(c, &motion).ok);
  const ScriptedBaseMotion scripted{ScriptedBaseMotionConfig{}};
  EXPECT_TRUE(motion->At(3.3).T_world_base.isApprox(scripted.At(3.3).T_world_base, 0.0));
  EXPECT_EQ(motion->Duration(), scripted.Duration());
  std::string error;
  c.type = CarrierType::kHandheld;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("handheld.waypoints"), std::string::npos) << error;
  c.handheld = RoomWalk();
  c.handheld.speed_mps = 5.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("handheld.speed_mps"), std::string::npos) << error;
  c.handheld = RoomWalk();
  c.handheld.closed_loop = false;
  c.handheld.laps = 2;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("closed_loop"), std::string::npos) << error;
  c.handheld = RoomWalk();
  c.handheld.waypoints[2] = {6.01, 0.0, 0.0};
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("handheld.waypoints[2]"), std::string::npos) << error;
  c.type = CarrierType::kCar;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("car.waypoints_file"), std::string::npos) << error;
  c.car.waypoints_file = "/nonexistent/route.csv";
  const Status st = MakeCarrierMotion(c, &motion);
  EXPECT_NE(st.message.find("/nonexistent/route.csv: cannot open"), std::string::npos) << st.message;
}

std::string Emit(const CarrierConfig& c) {
  YAML::Emitter out;
  EmitCarrierConfig(out, c);
  return out.c_str();
}

TEST(CarrierYaml, RoundTripOfEveryType) {
  std::vector<CarrierConfig> configs(5);
  configs[0].scripted_loop.loop_period_s = 25.0;
  configs[1].type = CarrierType::kHandheld;
  configs[1].handheld = RoomWalk();
  configs[1].handheld.laps = 3;
  configs[1].handheld.step_hz = 1.8;
  configs[2].type = CarrierType::kWheeled;
  configs[2].wheeled.waypoints = {{1, 2, 0.5}, {3, -4.25, 0}};
  configs[2].wheeled.height_m = 0.42;
  configs[3].type = CarrierType::kCar;
  configs[3].car.waypoints_file = "/data/route.csv";
  configs[3].car.max_lateral_accel_mps2 = 3.1;
  configs[4].type = CarrierType::kKitti;
  configs[4].kitti.poses_file = "/data/00.txt";
  configs[4].kitti.times_file = "/data/times.txt";
  configs[4].kitti.start_yaw_rad = 0.7;
  for (const CarrierConfig& c : configs) {
    const std::string text = Emit(c);
    CarrierConfig back;
    ParseCarrierConfig("/cfg/sim.yaml", YAML::Load(text), &back);
    EXPECT_EQ(back.type, c.type);
    EXPECT_EQ(Emit(back), text);
  }
  CarrierConfig back;
  ParseCarrierConfig("/cfg/sim.yaml", YAML::Load(Emit(configs[1])), &back);
  ASSERT_EQ(back.handheld.waypoints.size(), 4u);
  EXPECT_EQ(back.handheld.waypoints[1].dwell_s, 3.0);
  EXPECT_EQ(back.handheld.laps, 3);
  EXPECT_EQ(back.handheld.step_hz, 1.8);
}

std::string ParseCarrierError(const std::string& text) {
  CarrierConfig c;
  try {
    ParseCarrierConfig("/cfg/sim.yaml", YAML::Load(text), &c);
  } catch (const yaml::ParseError& e) {
    EXPECT_EQ(c.type, CarrierType::kScriptedLoop) << "a failed parse must leave the config untouched";
    return e.what();
  }
  return "";
}

TEST(CarrierYaml, ErrorsNameFileLineAndFieldAndPathsResolve) {
  std::string e = ParseCarrierError("type: handheld\nhandheld:\n  waypoints: [[0, 0], [5, 0]]\n  sped: 2\n");
  EXPECT_NE(e.find("/cfg/sim.yaml:4"), std::string::npos) << e;
  EXPECT_NE(e.find("sped"), std::string::npos) << e;
  e = ParseCarrierError("type: handheld\nhandheld:\n  waypoints:\n    - [0, 0]\n    - [5]\n");
  EXPECT_NE(e.find("/cfg/sim.yaml:5"), std::string::npos) << e;
  EXPECT_NE(e.find("handheld.waypoints[1]"), std::string::npos) << e;
  e = ParseCarrierError("type: boat\n");
  EXPECT_NE(e.find("/cfg/sim.yaml:1"), std::string::npos) << e;
  EXPECT_NE(e.find("carrier.type"), std::string::npos) << e;
  e = ParseCarrierError("type: wheeled\nwheeled:\n  waypoints: [[0, 0], [5, 0]]\n  speed_mps: -1\n");
  EXPECT_NE(e.find("/cfg/sim.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("wheeled.speed_mps"), std::string::npos) << e;
  e = ParseCarrierError("type: car\ncar: {waypoints_file: r.csv, height_m: high}\n");
  EXPECT_NE(e.find("height_m"), std::string::npos) << e;
  CarrierConfig c;
  ParseCarrierConfig("/cfg/sim.yaml", YAML::Load("type: kitti\nkitti: {poses_file: ../data/00.txt}\n"), &c);
  EXPECT_EQ(c.kitti.poses_file, "/data/00.txt");
  EXPECT_EQ(c.kitti.times_file, "");
  ParseCarrierConfig("/cfg/sim.yaml", YAML::Load("type: car\ncar: {waypoints_file: /abs/r.csv}\n"), &c);
  EXPECT_EQ(c.car.waypoints_file, "/abs/r.csv");
  EXPECT_EQ(c.type, CarrierType::kCar);
}

}  // namespace
}  // namespace rotolidar::sim
