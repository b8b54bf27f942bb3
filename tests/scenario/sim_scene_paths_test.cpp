// `rotolidar sim --scene NAME` walks the scene's own path: the rig stays inside the scene for the whole run;
// a carrier that does not fit the scene fails before anything is written; the built-in default (box room,
// scripted loop) writes the same bytes whether the carrier is chosen from the scene or given; a scene's
// transmissive materials reach the caster unless the config lists them.
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "core/io/trajectory_io.hpp"
#include "sim/sim_runner.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {
namespace {

namespace fs = std::filesystem;

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

SimConfig FromScene(const std::string& scene, double duration_s) {
  SimConfig config = DefaultSimConfig();
  config.scene = scene;
  config.duration_s = duration_s;
  config.camera.enabled = false;
  config.carrier_from_scene = true;  // what `rotolidar sim --scene NAME` does
  return config;
}

TEST(SimScenePaths, TheLabRunStaysInsideTheLab) {
  const std::string dir = (fs::temp_directory_path() / "rotolidar_scenario_lab_paths").string();
  fs::remove_all(dir);
  SimSummary summary;
  const Status s = RunSimulation(FromScene("lab", 6.0), dir, &summary);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_NE(ReadAll(dir + "/sim_config.yaml").find("type: handheld"), std::string::npos);
  Scene lab;
  ASSERT_TRUE(LoadScene(ResolveScenePath("lab"), &lab).ok);
  Trajectory truth;
  ASSERT_TRUE(ReadTrajectory(dir + "/truth/base.tum", TrajectoryFormat::kTum, &truth).ok);
  ASSERT_GE(truth.size(), 6000u);  // 1 kHz
  for (const StampedPose& p : truth)
    ASSERT_TRUE(lab.bounds.contains(p.T_ref_body.translation())) << "t = " << p.t_s << " at "
                                                                 << p.T_ref_body.translation().transpose();
  // The handheld path starts at its first waypoint (1.5, 1.6): in room A, not at the box room's (0, 0).
  EXPECT_NEAR(truth.front().T_ref_body.translation().x(), 1.5, 0.05);
  EXPECT_NEAR(truth.front().T_ref_body.translation().y(), 1.6, 0.05);
  EXPECT_GT(truth.back().T_ref_body.translation().x(), 1.6);  // and it moves along its first leg (+x)
}

TEST(SimScenePaths, ACarrierThatLeavesTheSceneFailsBeforeWriting) {
  const std::string dir = (fs::temp_directory_path() / "rotolidar_scenario_lab_loop").string();
  fs::remove_all(dir);
  SimConfig config = FromScene("lab", 10.0);
  config.carrier_from_scene = false;  // --carrier scripted_loop: the box room's loop around (0, 0)
  config.carrier.type = CarrierType::kScriptedLoop;
  SimSummary summary;
  const Status s = RunSimulation(config, dir, &summary);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("crosses primitive 'west_pier_0'"), std::string::npos) << s.message;  // its west wall
  EXPECT_FALSE(fs::exists(dir + "/lidar.pcap"));
}

TEST(SimScenePaths, TheDefaultRunIsTheSameWhetherTheCarrierIsChosenOrGiven) {
  const std::string a = (fs::temp_directory_path() / "rotolidar_scenario_default_chosen").string();
  const std::string b = (fs::temp_directory_path() / "rotolidar_scenario_default_given").string();
  SimConfig chosen = FromScene("box_room", 1.0);  // the demo's scene: no paths, the scripted loop fits
  SimConfig given = chosen;
  given.carrier_from_scene = false;
  SimSummary summary;
  ASSERT_TRUE(RunSimulation(chosen, a, &summary).ok);
  ASSERT_TRUE(RunSimulation(given, b, &summary).ok);
  for (const char* f : {"lidar.pcap", "imu.csv", "encoder.csv", "calib.yaml", "sim_config.yaml", "truth/base.tum"})
    EXPECT_EQ(ReadAll(a + "/" + f), ReadAll(b + "/" + f)) << f;
  EXPECT_NE(ReadAll(a + "/sim_config.yaml").find("type: scripted_loop"), std::string::npos);
}

TEST(SimScenePaths, ASceneDeclaresItsTransmissiveMaterialsToTheCaster) {
  const std::string tmp = fs::temp_directory_path().string();
  const auto run = [&](const std::string& name, const SimConfig& config) {
    const std::string dir = tmp + "/rotolidar_scenario_glass_" + name;
    fs::remove_all(dir);
    SimSummary summary;
    const Status s = RunSimulation(config, dir, &summary);
    EXPECT_TRUE(s.ok) << s.message;
    return dir;
  };
  const SimConfig from_scene = FromScene("glass_atrium", 0.5);  // glass: transmittance 0.9 in the scene file
  SimConfig listed = from_scene, other = from_scene;
  listed.lidar.material_transmittance = {{"glass", 0.9}};
  other.lidar.material_transmittance = {{"glass", 0.5}};  // the config wins over the scene
  const std::string a = run("scene", from_scene), b = run("listed", listed), c = run("other", other);
  SimConfig resolved;
  ASSERT_TRUE(LoadSimConfig(a + "/sim_config.yaml", &resolved).ok);
  EXPECT_EQ(resolved.lidar.material_transmittance, (std::vector<std::pair<std::string, double>>{{"glass", 0.9}}));
  ASSERT_TRUE(LoadSimConfig(c + "/sim_config.yaml", &resolved).ok);
  EXPECT_EQ(resolved.lidar.material_transmittance, (std::vector<std::pair<std::string, double>>{{"glass", 0.5}}));
  const std::string pcap = ReadAll(a + "/lidar.pcap");
  EXPECT_GT(pcap.size(), 100000u);
  EXPECT_EQ(pcap, ReadAll(b + "/lidar.pcap"));  // declared in the scene = listed in the config
  EXPECT_NE(pcap, ReadAll(c + "/lidar.pcap"));  // a different transmittance changes what the head sees
}

}  // namespace
}  // namespace rotolidar::sim
