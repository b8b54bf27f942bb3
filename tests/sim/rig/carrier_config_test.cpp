// Carrier path files, configs and YAML: errors name file:line and field; round trips.
#include "sim/rig/carrier_paths.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>


#include "tests/sim/rig/carrier_test_util.hpp"

namespace rotolidar::sim {
namespace {

using namespace carrier_test;

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
    const Status s = ParseCarrierConfig("/cfg/sim.yaml", YAML::Load(text), &back);
    ASSERT_TRUE(s.ok) << s.message;
    EXPECT_EQ(back.type, c.type);
    EXPECT_EQ(Emit(back), text);
  }
  CarrierConfig back;
  ASSERT_TRUE(ParseCarrierConfig("/cfg/sim.yaml", YAML::Load(Emit(configs[1])), &back).ok);
  ASSERT_EQ(back.handheld.waypoints.size(), 4u);
  EXPECT_EQ(back.handheld.waypoints[1].dwell_s, 3.0);
  EXPECT_EQ(back.handheld.laps, 3);
  EXPECT_EQ(back.handheld.step_hz, 1.8);
}

std::string ParseCarrierError(const std::string& text) {
  CarrierConfig c;
  const Status s = ParseCarrierConfig("/cfg/sim.yaml", YAML::Load(text), &c);
  if (s.ok) return "";
  EXPECT_EQ(c.type, CarrierType::kScriptedLoop) << "a failed parse must leave the config untouched";
  return s.message;
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
  ASSERT_TRUE(ParseCarrierConfig("/cfg/sim.yaml", YAML::Load("type: kitti\nkitti: {poses_file: ../data/00.txt}\n"), &c).ok);
  EXPECT_EQ(c.kitti.poses_file, "/data/00.txt");
  EXPECT_EQ(c.kitti.times_file, "");
  ASSERT_TRUE(ParseCarrierConfig("/cfg/sim.yaml", YAML::Load("type: car\ncar: {waypoints_file: /abs/r.csv}\n"), &c).ok);
  EXPECT_EQ(c.car.waypoints_file, "/abs/r.csv");
  EXPECT_EQ(c.type, CarrierType::kCar);
}


}  // namespace
}  // namespace rotolidar::sim
