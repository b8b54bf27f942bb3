// Fuzz targets of the YAML edges outside core/io: the estimator config, the sim config and scene files.
#include "tests/fuzz/fuzz_target.hpp"

#include "bench/cli/commands.hpp"
#include "sim/sim_config.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::fuzz {
namespace {

ROTOLIDAR_FUZZ_TARGET(slam_config) {
  EstimatorConfig config;
  (void)bench::LoadSlamConfig(WriteInput(data, size, "slam.yaml"), &config);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(sim_config) {
  sim::SimConfig config;
  (void)sim::LoadSimConfig(WriteInput(data, size, "sim.yaml"), &config);
  return 0;
}

ROTOLIDAR_FUZZ_TARGET(scene_yaml) {
  sim::Scene scene;
  (void)sim::LoadScene(WriteInput(data, size, "scene.yaml"), &scene);
  return 0;
}

}  // namespace
}  // namespace rotolidar::fuzz
