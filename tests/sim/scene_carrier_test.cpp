// The carrier a scene gives a run (sim/scene_carrier.hpp) and the path check: the default carrier per scene,
// every shipped default path passes, paths that leave the bounds or cross a wall fail naming the waypoint leg
// and the primitive; unknown scenes list the available ones (sim_config.hpp); a non-empty recording folder is
// refused unless forced, which clears only the previous recording (sim_runner.hpp).
#include <chrono>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "sim/scene_carrier.hpp"
#include "sim/sim_config.hpp"
#include "sim/sim_runner.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

struct Loaded {
  Scene scene;
  std::unique_ptr<EmbreeScene> embree;
};

Loaded Load(const std::string& name) {
  Loaded l;
  const Status s = LoadScene(ResolveScenePath(name), &l.scene);
  ROTOLIDAR_CHECK(s.ok, s.message);
  const Status e = EmbreeScene::Create(l.scene, &l.embree);
  ROTOLIDAR_CHECK(e.ok, e.message);
  return l;
}

Status Check(const Loaded& l, const CarrierConfig& carrier, double duration_s) {
  std::unique_ptr<BaseMotion> motion;
  if (Status s = MakeCarrierMotion(carrier, &motion); !s) return s;
  return CheckCarrierPath(carrier, *motion, duration_s, l.scene, *l.embree);
}

TEST(SceneCarrier, DefaultCarrierPerScene) {
  const std::pair<const char*, CarrierType> expected[] = {{"lab", CarrierType::kHandheld},
                                                          {"parking", CarrierType::kHandheld},
                                                          {"urban_loop", CarrierType::kCar},  // its only path
                                                          {"box_room", CarrierType::kScriptedLoop}};  // no paths
  for (const auto& [name, type] : expected) {
    Scene scene;
    ASSERT_TRUE(LoadScene(ResolveScenePath(name), &scene).ok) << name;
    CarrierConfig c;
    c.type = CarrierType::kWheeled;
    ChooseSceneCarrier(scene, &c);
    EXPECT_EQ(c.type, type) << name;
  }
  Scene lab;
  ASSERT_TRUE(LoadScene(ResolveScenePath("lab"), &lab).ok);
  EXPECT_EQ(SceneCarriers(lab), (std::vector<std::string>{"handheld", "wheeled"}));  // the file's order
}

TEST(SceneCarrier, EveryShippedDefaultPathStaysInsideItsScene) {
  for (const std::string& name : AvailableScenes()) {
    const Loaded l = Load(name);
    for (const std::string& carrier : SceneCarriers(l.scene)) {
      CarrierConfig c;
      ASSERT_TRUE(CarrierTypeFromName(carrier, &c.type));
      ASSERT_TRUE(FillScenePath(l.scene, &c).ok);
      std::unique_ptr<BaseMotion> motion;
      ASSERT_TRUE(MakeCarrierMotion(c, &motion).ok) << name << "/" << carrier;
      const double duration = std::min(motion->Duration(), 600.0);
      const Status s = CheckCarrierPath(c, *motion, duration, l.scene, *l.embree);
      EXPECT_TRUE(s.ok) << name << "/" << carrier << ": " << s.message;
    }
  }
}

TEST(SceneCarrier, TheDemoLoopFitsTheBoxRoomButNotTheLab) {
  CarrierConfig loop;  // the scripted loop around (0, 0): the box room's, the lab's corner
  const Status box = Check(Load("box_room"), loop, 60.0);
  EXPECT_TRUE(box.ok) << box.message;
  const Status s = Check(Load("lab"), loop, 20.0);
  ASSERT_FALSE(s.ok);
  // It starts at (3.25, 0, 1.2), touching the lab's south wall (a graze), and a quarter lap later walks out
  // through the west wall.
  EXPECT_NE(s.message.find("scripted_loop path crosses primitive 'west_pier_0' at t = 5.00 s"), std::string::npos)
      << s.message;
  EXPECT_NE(s.message.find("scripted loop around (0.00, 0.00)"), std::string::npos) << s.message;
  loop.scripted_loop.center_x_m = 4.0, loop.scripted_loop.center_y_m = 3.5;  // around the lab's round column: through the desks
  EXPECT_FALSE(Check(Load("lab"), loop, 20.0).ok);
}

TEST(SceneCarrier, APathThroughAWallNamesTheWaypointAndTheWall) {
  const Loaded lab = Load("lab");
  CarrierConfig c;
  c.type = CarrierType::kHandheld;
  // Room A's middle, then straight east through the partition (x 7.925..8.075) beside its doors.
  c.handheld.waypoints = {{6.5, 2.5, 0.0}, {10.0, 2.5, 0.0}, {10.0, 1.5, 0.0}};
  const Status s = Check(lab, c, 30.0);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("crosses primitive 'partition_1'"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("from waypoint 0 (6.50, 2.50) to waypoint 1 (10.00, 2.50)"), std::string::npos)
      << s.message;
  EXPECT_NE(s.message.find("(7.9"), std::string::npos) << s.message;  // where: the partition's west face
  // Through the south door instead (y 1.0..2.0): clear.
  c.handheld.waypoints = {{6.5, 1.5, 0.0}, {10.0, 1.5, 0.0}, {10.0, 2.5, 0.0}};
  const Status ok = Check(lab, c, 30.0);
  EXPECT_TRUE(ok.ok) << ok.message;
}

TEST(SceneCarrier, APathOutOfTheBoundsNamesTheWaypointAndTheBound) {
  const Loaded street = Load("clean_street");  // open: no wall stops the path, the bounds do
  CarrierConfig c;
  c.type = CarrierType::kWheeled;
  c.wheeled.waypoints = {{150.0, 0.0, 0.0}, {195.0, 0.0, 0.0}, {230.0, 0.0, 0.0}};
  const Status s = Check(street, c, 200.0);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("x 200.0"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("> bounds max 200.00"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("from waypoint 1 (195.00, 0.00) to waypoint 2 (230.00, 0.00)"), std::string::npos)
      << s.message;
}

TEST(SceneCarrier, AMissingScenePathListsWhatTheSceneOffers) {
  Scene urban;
  ASSERT_TRUE(LoadScene(ResolveScenePath("urban_loop"), &urban).ok);
  CarrierConfig c;
  c.type = CarrierType::kHandheld;
  const Status s = FillScenePath(urban, &c);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("no handheld path; it offers: car"), std::string::npos) << s.message;
  c.type = CarrierType::kCar;
  ASSERT_TRUE(FillScenePath(urban, &c).ok);
  EXPECT_EQ(c.car.waypoints.size(), urban.default_paths.at("car").size());
}

TEST(SceneCarrier, TheUrbanLoopCheckIsCheap) {
  const Loaded urban = Load("urban_loop");
  CarrierConfig c;
  c.type = CarrierType::kCar;
  ASSERT_TRUE(FillScenePath(urban.scene, &c).ok);
  const auto t0 = std::chrono::steady_clock::now();
  const Status s = Check(urban, c, 115.0);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(s.ok) << s.message;
  EXPECT_LT(wall_s, 1.0);  // 5,750 rays; the whole test, scene load included, took 0.13 s
}

TEST(SceneFiles, AnUnknownSceneListsTheAvailableOnes) {
  std::string path;
  const Status s = FindSceneFile("nosuch", &path);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("unknown scene 'nosuch'"), std::string::npos) << s.message;
  for (const char* name : {"box_room", "lab", "urban_loop", "parking"})
    EXPECT_NE(s.message.find(name), std::string::npos) << name << ": " << s.message;
  ASSERT_TRUE(FindSceneFile("lab", &path).ok);
  EXPECT_TRUE(std::filesystem::is_regular_file(path));
}

// A recording folder named like a scene (`rotolidar sim lab ...` writes ./lab) must not hide the scene `lab`.
TEST(SceneFiles, AFolderNamedLikeASceneDoesNotHideIt) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "rotolidar_scene_shadow_test";
  fs::remove_all(dir);
  fs::create_directories(dir / "lab");
  const fs::path cwd = fs::current_path();
  fs::current_path(dir);
  std::string path;
  const Status s = FindSceneFile("lab", &path);
  fs::current_path(cwd);
  fs::remove_all(dir);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(fs::path(path).filename(), "lab.yaml");
  EXPECT_TRUE(fs::is_regular_file(path));
}

TEST(RecordingDir, ANonEmptyFolderIsRefusedUnlessForced) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "rotolidar_prepare_recording_dir_test";
  fs::remove_all(dir);
  EXPECT_TRUE(PrepareRecordingDir(dir.string(), false).ok);  // absent
  fs::create_directories(dir);
  EXPECT_TRUE(PrepareRecordingDir(dir.string(), false).ok);  // empty
  fs::create_directories(dir / "truth");
  std::ofstream(dir / "lidar.pcap") << "old";
  std::ofstream(dir / "truth" / "base.tum") << "old";
  fs::create_directories(dir / "camera");
  std::ofstream(dir / "notes.txt") << "mine";
  const Status refused = PrepareRecordingDir(dir.string(), false);
  ASSERT_FALSE(refused.ok);
  EXPECT_NE(refused.message.find("not empty"), std::string::npos) << refused.message;
  EXPECT_NE(refused.message.find("--force"), std::string::npos) << refused.message;
  EXPECT_TRUE(fs::exists(dir / "lidar.pcap"));  // refusing touches nothing
  ASSERT_TRUE(PrepareRecordingDir(dir.string(), true).ok);
  EXPECT_FALSE(fs::exists(dir / "lidar.pcap"));
  EXPECT_FALSE(fs::exists(dir / "truth"));
  EXPECT_FALSE(fs::exists(dir / "camera"));
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));  // not a recording output
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rotolidar::sim
