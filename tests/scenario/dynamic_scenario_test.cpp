// Moving people out of the map, end to end: simulate a handheld walk through `lab_people` (six walkers, typical
// realism), run the core with and without its free-space test (core/pipeline/free_space.hpp), and score the
// dense map against the sim's truth of which returns hit a walker (truth/dynamic_hits.csv; bench's
// dynamic_share.hpp): the share of the walkers' seen voxels that the map kept.
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "bench/report/run_evaluation.hpp"
#include "bench/run/slam_run.hpp"
#include "sim/sim_runner.hpp"
#include "tests/scenario/scenario_sim.hpp"

namespace rotolidar::bench {
namespace {


/// The dense map's dynamic share and the ATE of one run of `recording` with `config`.
RunEvaluation SlamAndScore(const std::string& recording, const EstimatorConfig& config, const std::string& out) {
  SlamRunResult slam;
  const Status s = RunSlam(recording, config, out, &slam);
  EXPECT_TRUE(s.ok) << s.message;
  RunEvaluationOptions options;
  options.map_metrics = false;  // only the dynamic share (and the APE)
  options.completeness = false;
  RunEvaluation eval;
  const Status e = EvaluateRun(recording, out, slam, "", options, &eval);
  EXPECT_TRUE(e.ok) << e.message;
  EXPECT_TRUE(eval.has_dynamic) << eval.dynamic_note;
  std::printf("%s: ATE %.4f m; %s\n", out.c_str(), eval.ape.stats.rmse, DynamicShareLine(eval.dynamic).c_str());
  return eval;
}

/// A handheld walk through `scene` (typical realism, seed 1), simulated afresh into a temporary folder.
std::string SimulateHandheld(const std::string& scene, double duration_s, const std::string& name) {
  sim::SimConfig sim_config = sim::PresetSimConfig(sim::Realism::kTypical);
  sim_config.scene = scene;
  sim_config.duration_s = duration_s;
  sim_config.carrier.type = sim::CarrierType::kHandheld;
  return test_util::SimulateFresh(sim_config, name);
}

TEST(DynamicScenario, FreeSpaceTestKeepsWalkersOutOfTheDenseMap) {
  const std::string dir = SimulateHandheld("lab_people", 12.0, "rotolidar_dynamic_scenario");
  ASSERT_FALSE(HasFailure());

  EstimatorConfig off;
  off.free_space.enabled = false;
  EstimatorConfig no_recheck;
  no_recheck.free_space.recheck_s = 0.0;
  const RunEvaluation without = SlamAndScore(dir + "/recording", off, dir + "/without");
  const RunEvaluation delayed_only = SlamAndScore(dir + "/recording", no_recheck, dir + "/delayed_only");
  const RunEvaluation with = SlamAndScore(dir + "/recording", EstimatorConfig(), dir + "/with");
  ASSERT_GT(with.dynamic.voxels_seen, 10000u);  // the walkers were seen
  // Measured, 12 s: without the test the map keeps 66.7 % of the walkers' seen voxels (seed 1). Over seeds 1-10
  // (`rotolidar sim S --scene lab_people --carrier handheld --camera off --duration 12 --seed N`, `rotolidar
  // slam S --out O`, and `free_space: {recheck_s: 0}` for the delayed test alone), median / p90 / worst:
  //   delayed test alone:        3.60 / 3.84 / 3.89 %
  //   with the recheck (default): 2.91 / 3.17 / 3.18 %, lower on every seed (seed 1: 3.27 -> 2.60 %);
  // ATE median 0.0073 m, p90 0.0086 m, worst 0.0093 m, the same with and without the recheck (the dense map
  // does not feed registration). Bounds: 4 % (1.26x the worst: a filter that stopped working gives ~67 %), the
  // recheck strictly lower than the delayed test alone on this seed, and 0.03 m (3.2x the worst ATE).
  EXPECT_GT(without.dynamic.share_of_seen, 0.5);
  EXPECT_LT(with.dynamic.share_of_seen, 0.04);
  EXPECT_LT(with.dynamic.share_of_seen, delayed_only.dynamic.share_of_seen);
  EXPECT_LT(with.ape.stats.rmse, 0.03);
}

// People walking with the rig: in `corridor_busy` eight people walk the corridor's axis at 1.3 m/s beside the
// rig's 1.2 m/s. The one ahead is never an arrival (its earlier body hid its present place), so only the vacated
// screen (core/pipeline/vacated_screen.hpp) keeps it out of registration.
TEST(DynamicScenario, ACrowdWalkingWithTheRigDoesNotCarryThePoseAlong) {
  const std::string dir = SimulateHandheld("corridor_busy", 20.0, "rotolidar_crowd_scenario");
  ASSERT_FALSE(HasFailure());

  EstimatorConfig unscreened;
  unscreened.free_space.vacated_radius_m = 0.0;
  const RunEvaluation without = SlamAndScore(dir + "/recording", unscreened, dir + "/without");
  const RunEvaluation with = SlamAndScore(dir + "/recording", EstimatorConfig(), dir + "/with");
  // Measured over seeds 1-10 (`rotolidar study bench/studies/crowded_seeds.yaml`): ATE median / p90 / worst
  // 0.0158 / 0.0201 / 0.0226 m (seed 1: 0.0159 m). Without the vacated screen seeds 1-6 gave 1.01-1.36 m (seed 1:
  // 1.20 m; the velocity along the corridor decays to -0.5 m/s). Bounds: 0.05 m (2.2x the worst seed), and 0.3 m
  // the other way, so that the test also says when the screen is no longer what holds the pose.
  EXPECT_LT(with.ape.stats.rmse, 0.05);
  EXPECT_GT(without.ape.stats.rmse, 0.3);
}

}  // namespace
}  // namespace rotolidar::bench
