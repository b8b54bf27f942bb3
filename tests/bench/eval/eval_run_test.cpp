// eval_run: options validation, file-based APE/RPE runs, table and JSON output.
#include <cmath>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bench/run/eval_run.hpp"

namespace rotolidar::bench {
namespace {

Trajectory Circle(int n, double radius_m, double t0) {
  Trajectory traj;
  for (int i = 0; i < n; ++i) {
    const double a = 0.1 * i;
    Pose3 T = RotZ(a);
    T.translation() = Eigen::Vector3d(radius_m * std::cos(a), radius_m * std::sin(a), 0.05 * i);
    traj.push_back({t0 + 0.1 * i, T});
  }
  return traj;
}

TEST(EvalRun, ValidateNamesTheField) {
  EvalOptions o;
  std::string err;
  EXPECT_FALSE(o.Validate(&err));
  EXPECT_NE(err.find("ref_path"), std::string::npos);
  o.ref_path = "a";
  o.est_path = "b";
  EXPECT_TRUE(o.Validate(&err));
  o.metric = EvalMetric::kRpe;
  o.delta = 2.5;
  EXPECT_FALSE(o.Validate(&err));
  EXPECT_NE(err.find("delta"), std::string::npos);
}

// A rigidly moved estimate (with 3 ms timestamp jitter) has zero APE after SE(3) alignment.
TEST(EvalRun, TumApeOfRigidlyMovedEstimateIsZeroAfterAlignment) {
  const Trajectory ref = Circle(60, 5.0, 100.0);
  Trajectory est = ref;
  Pose3 G = RotZ(0.7);
  G.translation() = Eigen::Vector3d(1, 2, 3);
  for (auto& sp : est) {
    sp.T_ref_body = G * sp.T_ref_body;
    sp.t_s += 0.003;
  }
  const std::string dir = testing::TempDir();
  ASSERT_TRUE(WriteTrajectory(dir + "/ev_ref.tum", TrajectoryFormat::kTum, ref).ok);
  ASSERT_TRUE(WriteTrajectory(dir + "/ev_est.tum", TrajectoryFormat::kTum, est).ok);
  EvalOptions o;
  o.ref_path = dir + "/ev_ref.tum";
  o.est_path = dir + "/ev_est.tum";
  o.align = Alignment::kSe3;
  o.json_path = dir + "/ev.json";
  EvalResult r;
  const Status s = RunEval(o, &r);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(r.num_associated, 60u);
  EXPECT_LT(r.stats.max, 1e-9);
  std::ifstream in(o.json_path);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["stats"]["max"].get<double>(), r.stats.max);
  std::ostringstream table;
  PrintEvalStats(r, table);
  EXPECT_NE(table.str().find("rmse"), std::string::npos);

  o.align = Alignment::kNone;  // unaligned: error is at least the 1 m + ... offset
  ASSERT_TRUE(RunEval(o, &r).ok);
  EXPECT_GT(r.stats.min, 1.0);
}

TEST(EvalRun, ComputeApeAndFailures) {
  const Trajectory ref = Circle(30, 2.0, 0.0);
  EvalResult r = ComputeApe(ref, ref, Alignment::kSim3);
  ASSERT_TRUE(r.status.ok) << r.status.message;
  EXPECT_NEAR(r.alignment.scale, 1.0, 1e-12);
  EXPECT_LT(r.stats.rmse, 1e-12);
  r = ComputeApe(ref, Circle(30, 2.0, 50.0), Alignment::kNone);
  EXPECT_FALSE(r.status.ok);  // no timestamps in common

  EvalOptions o;
  o.ref_path = testing::TempDir() + "/missing_ref.txt";
  o.est_path = o.ref_path;
  EXPECT_FALSE(RunEval(o, &r).ok);
  EXPECT_NE(r.status.message.find("missing_ref.txt"), std::string::npos);
}

}  // namespace
}  // namespace rotolidar::bench
