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

#include "tests/sim/rig/carrier_test_util.hpp"

namespace rotolidar::sim {
namespace {

using namespace carrier_test;

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


}  // namespace
}  // namespace rotolidar::sim
