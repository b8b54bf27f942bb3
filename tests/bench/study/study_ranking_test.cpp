// Ranking configurations over seeds (study_ranking.hpp): per partition (scene), Borda score over the rank_by
// metrics with each metric's direction, failed seeds rank a configuration last, Welch's t against the best.
#include <cmath>

#include <gtest/gtest.h>

#include "bench/study/study_ranking.hpp"

namespace rotolidar::bench {
namespace {

size_t Column(const std::string& name) {
  for (size_t i = 0; i < StudyMetrics().size(); ++i)
    if (StudyMetrics()[i].name == name) return i;
  return 0;
}

/// A point of scene `scene`, speed `speed`, seed `seed` with the given ATE and coverage.
StudyPointResult Point(const std::string& scene, const std::string& speed, int seed, double ate, double cov,
                       bool failed = false) {
  StudyPointResult r;
  r.point.swept = {{"scene", scene}, {"speed", speed}, {"seed", std::to_string(seed)}};
  r.point.id = "scene-" + scene + "__speed-" + speed + "__seed-" + std::to_string(seed);
  r.state = failed ? PointState::kFailed : PointState::kRan;
  r.metrics.assign(StudyMetrics().size(), std::nan(""));
  r.metrics[Column("ate_rmse_m")] = ate;
  r.metrics[Column("coverage_total")] = cov;
  return r;
}

TEST(StudyRankingTest, RanksPerSceneWithDirectionsAndFailures) {
  StudyResult res;
  for (int s = 1; s <= 3; ++s) {
    const double d = 0.001 * s;
    res.points.push_back(Point("lab", "1.3", s, 0.020 + d, 0.30 + d));  // worse ATE, worse coverage
    res.points.push_back(Point("lab", "2.6", s, 0.010 + d, 0.40 + d));  // best on both
    res.points.push_back(Point("lab", "5.2", s, 0.005 + d, 0.50 + d, s == 2));  // best values but one seed failed
    res.points.push_back(Point("hall", "1.3", s, 0.010 + d, 0.45 + d));  // in the hall the slow speed wins
    res.points.push_back(Point("hall", "2.6", s, 0.030 + d, 0.20 + d));
  }
  const std::vector<RankedGroup> g = RankStudyGroups(res, {"ate_rmse_m", "coverage_total"});
  ASSERT_EQ(g.size(), 5u);
  EXPECT_EQ(g[0].partition, "scene=lab");
  EXPECT_EQ(g[0].design, "speed=2.6");
  EXPECT_EQ(g[0].rank, 1);
  EXPECT_EQ(g[0].t_vs_best, 0.0);
  EXPECT_EQ(g[1].design, "speed=1.3");
  EXPECT_EQ(g[2].design, "speed=5.2");  // the failed seed puts it last despite the best means
  EXPECT_EQ(g[2].failed, 1u);
  EXPECT_EQ(g[2].metrics[0].n, 2u);
  EXPECT_EQ(g[3].partition, "scene=hall");
  EXPECT_EQ(g[3].design, "speed=1.3");
  EXPECT_EQ(g[3].rank, 1);
  EXPECT_NEAR(g[0].metrics[0].mean, 0.012, 1e-12);
  EXPECT_NEAR(g[0].metrics[0].sd, 0.001, 1e-12);
  EXPECT_NEAR(g[0].metrics[1].min, 0.401, 1e-12);
  EXPECT_NEAR(g[0].metrics[1].max, 0.403, 1e-12);
  // 1.3 vs 2.6 in the lab: means 0.022 vs 0.012, sd 0.001 each over 3 seeds: t = 0.01 / sqrt(2e-6 / 3).
  EXPECT_NEAR(g[1].t_vs_best, 0.01 / std::sqrt(2e-6 / 3), 1e-6);
  EXPECT_TRUE(RankStudyGroups(res, {}).empty());
  EXPECT_TRUE(HigherIsBetter("coverage_total"));
  EXPECT_FALSE(HigherIsBetter("map_to_truth_median_m"));
}

}  // namespace
}  // namespace rotolidar::bench
