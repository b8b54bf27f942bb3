// The camera where the LiDAR is blind along one axis: the clean street (flat ground between two smooth walls, so
// translation along the street is unobservable from geometry; textured facades). Typical realism, seed 1, the
// scene's handheld path. The same recording runs LiDAR-inertial and LiDAR-visual-inertial (visual.enabled); the
// camera must hold the street's axis.
#include <algorithm>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "bench/run/slam_run.hpp"
#include "bench/run/truth_eval.hpp"
#include "sim/sim_runner.hpp"
#include "tests/scenario/scenario_sim.hpp"

namespace rotolidar::bench {
namespace {

TEST(VisualScenario, TheCameraHoldsTheCleanStreetsAxis) {
  sim::SimConfig sim_config = sim::PresetSimConfig(sim::Realism::kTypical);
  sim_config.scene = "clean_street";
  sim_config.duration_s = 40.0;
  sim_config.carrier.type = sim::CarrierType::kHandheld;
  const std::string dir = test_util::SimulateFresh(sim_config, "rotolidar_visual_scenario");
  ASSERT_FALSE(HasFailure());

  EstimatorConfig lidar_inertial, with_camera;
  with_camera.visual.enabled = true;
  SlamRunResult li, lvi;
  ASSERT_TRUE(RunSlam(dir + "/recording", lidar_inertial, dir + "/li", &li).ok);
  ASSERT_TRUE(RunSlam(dir + "/recording", with_camera, dir + "/lvi", &lvi).ok);
  EvalResult li_ate, lvi_ate;
  ASSERT_TRUE(EvaluateAgainstTruth(dir + "/recording", li.trajectory, &li_ate).ok);
  ASSERT_TRUE(EvaluateAgainstTruth(dir + "/recording", lvi.trajectory, &lvi_ate).ok);

  std::vector<int> observations;
  int with_image = 0, lidar_depths = 0;
  for (const ScanReport& r : lvi.scans) {
    if (!r.visual.image) continue;
    ++with_image;
    observations.push_back(r.visual.observations);
    lidar_depths += r.visual.lidar_depths;
  }
  ASSERT_FALSE(observations.empty());
  std::nth_element(observations.begin(), observations.begin() + observations.size() / 2, observations.end());
  const int median_observations = observations[observations.size() / 2];
  std::printf("ATE LiDAR-inertial %.4f m, with the camera %.4f m (%.3fx); %d of %zu scans with an image, median %d "
              "observations, %d LiDAR depths\n",
              li_ate.stats.rmse, lvi_ate.stats.rmse, lvi_ate.stats.rmse / li_ate.stats.rmse, with_image,
              lvi.scans.size(), median_observations, lidar_depths);
  // The goal is 0.2x of LiDAR-inertial on this scene; measured on 60 s of it (seed 1): 16.98 -> 0.053 m (0.003x).
  EXPECT_LT(lvi_ate.stats.rmse, 0.2 * li_ate.stats.rmse);
  EXPECT_LT(lvi_ate.stats.rmse, 0.3);
  EXPECT_GT(with_image, int(0.9 * lvi.scans.size()));  // the camera runs at 30 Hz, the scans at 10 Hz
  EXPECT_GT(median_observations, 50);
  EXPECT_GT(lidar_depths, 0);
}

}  // namespace
}  // namespace rotolidar::bench
