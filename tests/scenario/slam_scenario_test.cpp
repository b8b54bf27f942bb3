// The LiDAR-inertial core end to end on the seed's scenes: simulate a short handheld segment (the scene's walk),
// run the LiDAR-inertial estimator on the recording (bench RunSlam), and bound the ATE (SE(3) Umeyama) against
// the sim's truth/base.tum. Short segments keep this binary well under 3 minutes on a 2-core machine.
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include "bench/run/slam_run.hpp"
#include "bench/run/truth_eval.hpp"
#include "core/io/trajectory_io.hpp"
#include "sim/sim_runner.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

struct ScenarioResult {
  SlamRunResult slam;
  Trajectory truth;  ///< truth/base.tum
  EvalResult ape;
};

/// Simulates `seconds` of the scene's handheld walk (seed 1) under `realism` and runs the estimator (`config`;
/// its range sigma comes from calib.yaml) in its own folder, named by the scene and `tag`.
ScenarioResult RunScenario(const std::string& scene, double seconds, const EstimatorConfig& config = {},
                           const std::string& tag = "", sim::Realism realism = sim::Realism::kTypical) {
  sim::SimConfig sim_config = sim::PresetSimConfig(realism);  // typical: the twin's default realism
  sim_config.scene = scene;
  sim_config.duration_s = seconds;
  sim_config.carrier.type = sim::CarrierType::kHandheld;
  // No camera frames unless the run reads them (rendering costs most of a scenario's time; the LiDAR, IMU and
  // encoder streams have their own random streams, so they are the same bytes either way).
  sim_config.camera.enabled = config.visual.enabled;
  const std::string dir = (fs::temp_directory_path() / ("rotolidar_slam_scenario_" + scene + tag)).string();
  fs::remove_all(dir);
  sim::SimSummary summary;
  const Status sim_status = sim::RunSimulation(sim_config, dir + "/recording", &summary);
  EXPECT_TRUE(sim_status.ok) << sim_status.message;
  ScenarioResult r;
  const Status slam_status = RunSlam(dir + "/recording", config, dir + "/slam", &r.slam);
  EXPECT_TRUE(slam_status.ok) << slam_status.message;
  const Status eval_status = EvaluateAgainstTruth(dir + "/recording", r.slam.trajectory, &r.ape);
  EXPECT_TRUE(eval_status.ok) << eval_status.message;
  const Status truth_status = ReadTrajectory(dir + "/recording/truth/base.tum", TrajectoryFormat::kTum, &r.truth);
  EXPECT_TRUE(truth_status.ok) << truth_status.message;
  std::printf("%s %.0f s: ATE RMSE %.4f m over %zu poses\n", scene.c_str(), seconds, r.ape.stats.rmse,
              r.ape.num_associated);
  return r;
}

/// Median over the registered scans of the weakest direction's generalised eigenvalue (how well the LiDAR alone
/// pins the least observed direction; dimensionless, see core/registration/degeneracy.hpp).
double MedianWeakestLambda(const ScenarioResult& r) {
  std::vector<double> lambda0;
  for (const ScanReport& s : r.slam.scans)
    if (s.registration.attempted) lambda0.push_back(s.degeneracy.eigenvalues(0));
  if (lambda0.empty()) return 0.0;
  std::nth_element(lambda0.begin(), lambda0.begin() + lambda0.size() / 2, lambda0.end());
  return lambda0[lambda0.size() / 2];
}

void ExpectHealthy(const ScenarioResult& r, double seconds) {
  EXPECT_EQ(r.slam.bad_packets, 0u);
  EXPECT_GE(r.slam.scans.size(), size_t(seconds * 10) - 2);  // 10 Hz head
  size_t imu_scans = 0;
  for (const ScanReport& s : r.slam.scans) imu_scans += s.imu_initialized ? 1 : 0;
  // The handheld walk starts at rest: the IMU initialises (static start) after imu_init_scans = 10 scans.
  EXPECT_GE(imu_scans, r.slam.scans.size() - 12);
  // The pose is held while the IMU is still (the walk sets off after ~2.2 s), across the IMU's initialisation:
  // a prefix of scans after the first (measured 26 on lab and corridor: the stillness test looks back 1 s), and
  // none once the rig moved.
  size_t held = 0;
  bool moved = false;
  for (size_t i = 1; i < r.slam.scans.size(); ++i) {
    const ScanReport& s = r.slam.scans[i];
    moved = moved || !s.held_static;
    EXPECT_FALSE(s.held_static && moved) << s.t_start_s;
    held += s.held_static ? 1 : 0;
  }
  EXPECT_GE(held, 15u);
  EXPECT_LE(held, 32u);
  // The hand-over from the held pose to the window is continuous: through the hold and the first two scans
  // after it, each scan-to-scan rotation matches the truth's (nearest truth pose in time) within 0.1 deg. The
  // hold used to end at IMU initialisation with a 1.2-1.4 deg step (a young map's registration pulled it).
  const Trajectory& t = r.slam.trajectory;
  const auto truth_at = [&](Seconds ts) {
    return std::min_element(r.truth.begin(), r.truth.end(), [&](const StampedPose& a, const StampedPose& b) {
             return std::abs(a.t_s - ts) < std::abs(b.t_s - ts);
           })->T_ref_body.linear();
  };
  ASSERT_FALSE(r.truth.empty());
  for (size_t i = 1; i < std::min(t.size(), held + 3); ++i) {
    const Eigen::Matrix3d est = t[i - 1].T_ref_body.linear().transpose() * t[i].T_ref_body.linear();
    const Eigen::Matrix3d tru = truth_at(t[i - 1].t_s).transpose() * truth_at(t[i].t_s);
    const double error_deg = Eigen::AngleAxisd(tru.transpose() * est).angle() * 180 / M_PI;
    EXPECT_LT(error_deg, 0.1) << "pose " << i << " at " << t[i].t_s << " s";
  }
}

TEST(SlamScenario, LabHandheld) {
  const double seconds = 8.0;
  const ScenarioResult r = RunScenario("lab", seconds);
  ExpectHealthy(r, seconds);
  std::printf("lab: median weakest lambda %.4f\n", MedianWeakestLambda(r));
  // Typical realism over seeds 1-10 (bench/studies/scenario_seeds.yaml: `rotolidar study` runs these exact
  // segments; study_seeds.csv; with the incidence-aware feature gate, the 160-keyframe map and the still test
  // on 0.2 s means, the plane residuals' incidence weights): median 0.0061 m, p90 0.0087 m, worst 0.0089 m; the
  // bound is 2x the worst.
  // Ideal realism (seed 1, 8 s: ~2.2 s at rest, ~6 m walked): 0.0109 m RMSE (0.0131 m with a keyframe every
  // scan, exact neighbour reuse and denser planar sets; 0.0143 m before the visibility check and 5 neighbours;
  // 0.0243 m without the static-start hold: the first bands drifted 3.8 deg). ~3x headroom. Frame, time or
  // gravity bugs gave decimetres to metres while this was built.
  EXPECT_LT(r.ape.stats.rmse, 0.02);
}

// The harsh twin: a rougher stepper (its 50- and 200-step lines shake the standing rig to 0.4 m/s^2 per axis),
// an uncalibrated IMU (2 % scale, 10 mrad misalignment, 1 deg/s turn-on bias), 1.5x noisier ranges that grow
// 5.7x at 60 deg incidence, mixed edge points. Every harsh run diverged (lab 20 s seeds 1-5: 30-93 m) while the
// per-sample still test took the shake for motion: the static start was not held, and the few bands of a young
// map, registered by a noisy LiDAR, drifted into the IMU's initialisation. The still test now judges 0.2 s means.
TEST(SlamScenario, LabHandheldHarsh) {
  const double seconds = 8.0;
  const ScenarioResult r = RunScenario("lab", seconds, {}, "_harsh", sim::Realism::kHarsh);
  ExpectHealthy(r, seconds);
  // Harsh, seeds 1-10 (bench/studies/scenario_seeds.yaml, lab_8s_harsh): median 0.0187 m, p90 0.0267 m, worst
  // 0.0272 m (typical: 0.0061 / 0.0087 / 0.0089 m); with the per-sample still test seed 1 ended at 16.5 m. The
  // bound is 2x the worst.
  EXPECT_LT(r.ape.stats.rmse, 0.06);
}

TEST(SlamScenario, CorridorHandheld) {
  // 20 s: ~2.2 s at rest, then ~20 m down the 90 m corridor, the west end wall 2 -> 22 m behind.
  const double seconds = 20.0;
  const ScenarioResult r = RunScenario("corridor", seconds);
  ExpectHealthy(r, seconds);
  const DegeneracyConfig d = EstimatorConfig().registration.degeneracy;
  size_t remapped = 0, weak = 0;
  for (const ScanReport& s : r.slam.scans) {
    remapped += s.degeneracy.degenerate ? 1 : 0;
    weak += s.registration.attempted && s.degeneracy.eigenvalues(0) < d.weak_eigenvalue ? 1 : 0;
  }
  std::printf("corridor: %zu of %zu scans weak along one direction, %zu remapped, median weakest lambda %.4f\n",
              weak, r.slam.scans.size(), remapped, MedianWeakestLambda(r));
  // The corridor is the degeneracy case: along its axis only the west end wall is seen. Under ideal realism the
  // registration's weakest direction stayed below weak_eigenvalue in 110 of 200 scans (0.0055 m RMSE, seed 1).
  // Under typical, with one range sigma for every return, only 3-4 of ~173 registered scans were (seeds 1-3):
  // the oblique walls' noise passed as edges whose fake information hid the axis. With the incidence-aware
  // feature gate: 95 / 87 / 95 of 173 (median weakest lambda 0.043 against the lab's 0.089), so the detector
  // sees the axis again; the bound is under half of that.
  EXPECT_GT(weak, 40u);
  // Typical, seeds 1-10 (bench/studies/scenario_seeds.yaml; with the incidence-aware feature gate and the
  // 160-keyframe map, the plane residuals' incidence weights): median 0.0046 m, p90 0.0060 m, worst 0.0063 m
  // (0.0055 / 0.0073 / 0.0077 m without the weights); the bound is 2x the worst. Before that
  // gate (one range sigma for every return) the noise on the oblique walls passed as edges: median 0.0253 m,
  // worst 0.0291 m, which fails.
  EXPECT_LT(r.ape.stats.rmse, 0.015);
}

TEST(SlamScenario, ParkingHandheld) {
  // The first 12 s of the 120 m walk around the parking lot (outdoor: cars, columns, far facades); the full loop
  // runs in the benchmark (`rotolidar bench slam --scene parking --duration 202`).
  const double seconds = 12.0;
  const ScenarioResult r = RunScenario("parking", seconds);
  ExpectHealthy(r, seconds);
  // Typical realism, seeds 1-10 (bench/studies/scenario_seeds.yaml; with the incidence-aware feature gate and
  // the 160-keyframe map, the plane residuals' incidence weights): median 0.0133 m, p90 0.0233 m, worst 0.0263 m
  // (0.0145 / 0.0227 / 0.0244 m without the weights; 0.0190 / 0.0251 / 0.0254 m before the
  // gate; seeds 1-5 gave median 0.0469 m, worst 0.0672 m before the static hold lasted through the IMU
  // initialisation); the bound is 1.5x the worst. Ideal realism
  // (seed 1, 12 s: ~2.2 s at rest, then ~11 m walked): 0.0153 m RMSE (0.0346 m with a keyframe every
  // scan, exact neighbour reuse and denser planar sets; 0.0406 m with the full planar set; 3-5 cm lateral errors
  // in the first seconds after the static initialisation; the full 202 s loop: 0.015 m). the loop's goal
  // is 0.10 m.
  EXPECT_LT(r.ape.stats.rmse, 0.04);
}

/// LiDAR-only (use_imu false) on the scene's first `seconds`: every packet decodes and the ATE RMSE stays below
/// bound_m [m].
void ExpectLidarOnlyWithin(const std::string& scene, double seconds, double bound_m) {
  EstimatorConfig config;
  config.use_imu = false;
  const ScenarioResult r = RunScenario(scene, seconds, config, "_lidar_only");
  EXPECT_EQ(r.slam.bad_packets, 0u);
  EXPECT_LT(r.ape.stats.rmse, bound_m);
}

// LiDAR-only (use_imu false) through the parking lot's first corner (a 90 deg turn in ~1 s at 36 s) and its
// sky-and-ground phases (the lateral axis weak for ~0.5 s every half rotor turn). Without an IMU the guess is the
// constant-velocity extrapolation: translation velocity over the last 0.9 s, rotation rate from the last two
// scans, up to 30 correspondence rebuilds, and the scan-side free-space screen. Typical, seeds 1-10 (`rotolidar
// sim R --scene parking --carrier handheld --camera off --duration 60 --seed N`, `rotolidar slam R --out O
// --config F`, F = `use_imu: false`): median 0.054 m, p90 0.061 m, worst 0.061 m. With the last two scans' twist
// and 12 rebuilds every seed diverged at the corner (4.5-21.7 m). The bound is 1.6x the worst seed.
TEST(SlamScenario, ParkingLidarOnlyThroughTheCorner) { ExpectLidarOnlyWithin("parking", 60.0, 0.1); }

// LiDAR-only along the 40 s corridor while a person walks towards the rig: the corridor's axis is weak, and the
// walker's features, matched against the walls behind, pushed the estimate along it (the scan-side screen keeps
// them out, at the LiDAR-only prediction). Typical, seeds 1-10 (`--scene corridor --duration 40`, as above):
// median 0.041 m, p90 0.060 m, worst 0.071 m; without the screen 9 of 10 seeds stayed within 0.07 m and seed 9
// diverged (2.75 m); with the last two scans' twist and 12 rebuilds 0.16-12.2 m. The bound is 1.7x the worst.
TEST(SlamScenario, CorridorWalkerLidarOnly) { ExpectLidarOnlyWithin("corridor", 40.0, 0.12); }

}  // namespace
}  // namespace rotolidar::bench
