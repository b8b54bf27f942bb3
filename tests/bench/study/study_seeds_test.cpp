// Statistics over seeds: groups are the points without their seed, percentiles are nearest-rank, failed runs are
// counted and never averaged in, and study.html shows the ATE table.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "bench/study/study_report.hpp"
#include "bench/study/study_seeds.hpp"

namespace rotolidar::bench {
namespace {

const double kNan = std::numeric_limits<double>::quiet_NaN();

size_t AteIndex() {
  for (size_t i = 0; i < StudyMetrics().size(); ++i)
    if (StudyMetrics()[i].name == "ate_rmse_m") return i;
  return 0;
}

StudyPointResult Point(const std::string& variant, int seed, double ate, PointState state = PointState::kRan) {
  StudyPointResult r;
  r.point.swept = {{"variant", variant}, {"seed", std::to_string(seed)}};
  r.point.id = "variant-" + variant + "__seed-" + std::to_string(seed);
  r.state = state;
  r.metrics.assign(StudyMetrics().size(), kNan);
  if (state != PointState::kFailed) r.metrics[AteIndex()] = ate;
  return r;
}

const SeedStatistics& Find(const std::vector<SeedStatistics>& stats, const std::string& group) {
  for (const SeedStatistics& s : stats)
    if (s.group == group && s.metric == "ate_rmse_m") return s;
  static const SeedStatistics none;
  ADD_FAILURE() << "no group " << group;
  return none;
}

TEST(StudySeeds, NearestRankPercentiles) {
  EXPECT_EQ(NearestRankPercentile({3, 1, 2}, 0.5), 2);
  EXPECT_EQ(NearestRankPercentile({4, 1, 3, 2}, 0.5), 2);  // rank ceil(2) = 2: no interpolation
  EXPECT_EQ(NearestRankPercentile({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}, 0.9), 9);
  EXPECT_EQ(NearestRankPercentile({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, 0.9), 10);  // rank ceil(9.9) = 10
  EXPECT_EQ(NearestRankPercentile({5, kNan, 7}, 0.0), 5);  // NaN ignored
  EXPECT_TRUE(std::isnan(NearestRankPercentile({kNan}, 0.5)));
}

TEST(StudySeeds, GroupsByEverythingButTheSeed) {
  StudyResult r;
  for (int seed = 1; seed <= 10; ++seed) r.points.push_back(Point("a", seed, 0.1 * (11 - seed)));  // 1.0 .. 0.1
  r.points.push_back(Point("b", 1, 0.5));
  r.points.push_back(Point("b", 2, kNan, PointState::kFailed));
  r.points.push_back(Point("b", 3, 0.7));
  const std::vector<SeedStatistics> stats = StudySeedStatistics(r);
  ASSERT_EQ(stats.size(), 2 * StudyMetrics().size());
  EXPECT_EQ(stats.front().group, "variant-a");  // expansion order
  const SeedStatistics& a = Find(stats, "variant-a");
  EXPECT_EQ(a.seeds, 10u);
  EXPECT_EQ(a.values, 10u);
  EXPECT_NEAR(a.median, 0.5, 1e-12);
  EXPECT_NEAR(a.p90, 0.9, 1e-12);
  EXPECT_NEAR(a.max, 1.0, 1e-12);
  EXPECT_NEAR(a.min, 0.1, 1e-12);
  const SeedStatistics& b = Find(stats, "variant-b");
  EXPECT_EQ(b.seeds, 3u);
  EXPECT_EQ(b.failed, 1u);  // counted apart, not a value
  EXPECT_EQ(b.values, 2u);
  EXPECT_NEAR(b.max, 0.7, 1e-12);

  const std::string csv = StudySeedsCsv(stats);
  EXPECT_EQ(csv.rfind("group,metric,seeds,failed,values,median,p90,min,max\n", 0), 0u);
  EXPECT_NE(csv.find("\"variant-b\",ate_rmse_m,3,1,2,0.5,0.7,0.5,0.7\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\"variant-a\",coverage_total,10,0,0,,,,\n"), std::string::npos);  // no values: empty

  StudyConfig config;
  const std::string html = StudyHtml(config, r, {});
  EXPECT_NE(html.find("<h2>Over seeds</h2>"), std::string::npos);
  EXPECT_NE(html.find("<td>variant-a</td><td>10</td><td>0</td><td>0.5000</td><td>0.9000</td><td>1.0000</td>"),
            std::string::npos);
}

TEST(StudySeeds, OnlyTheSeedSweptIsOneBaseGroup) {
  StudyPointResult p;
  p.point.swept = {{"seed", "4"}};
  EXPECT_EQ(GroupWithoutSeed(p.point), "base");
  p.point.swept = {{"scene", "lab"}, {"seed", "4"}, {"profile", "constant"}};
  EXPECT_EQ(GroupWithoutSeed(p.point), "scene-lab__profile-constant");
}

}  // namespace
}  // namespace rotolidar::bench
