// Registration problems of a run: consecutive scans with one problem form one stretch, scans that never
// attempted a registration are not problems, and the JSON counts what the stretches hold.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "bench/run/scan_health.hpp"

namespace rotolidar::bench {
namespace {

ScanReport Scan(int i, bool attempted, bool converged, bool degenerate = false) {
  ScanReport r;
  r.t_start_s = 100.0 + 0.1 * i;
  r.t_end_s = r.t_start_s + 0.1;
  r.registration.attempted = attempted;
  r.registration.converged = converged;
  if (attempted && !converged) r.registration.message = "no convergence in 12 rebuilds";
  r.degeneracy.degenerate = degenerate;
  if (degenerate) r.degeneracy.axis_weight << 0.1, 0.9, 0.0, 0.0, 0.0, 0.7;
  return r;
}

TEST(ScanHealth, ConsecutiveProblemsAreOneStretch) {
  std::vector<ScanReport> scans;
  scans.push_back(Scan(0, false, false));  // the first scan defines the map: not a failure
  for (int i = 1; i <= 3; ++i) scans.push_back(Scan(i, true, true));
  for (int i = 4; i <= 6; ++i) scans.push_back(Scan(i, true, false));  // one stretch of 3
  scans.push_back(Scan(7, true, true, true));                           // degenerate, converged
  scans.push_back(Scan(8, true, true));
  scans.push_back(Scan(9, true, false, true));  // both problems at once: one stretch of each kind
  const ScanHealth h = AssessScanHealth(scans);
  EXPECT_EQ(h.scans, 10u);
  EXPECT_EQ(h.not_converged, 4u);
  EXPECT_EQ(h.degenerate, 2u);
  ASSERT_EQ(h.stretches.size(), 4u);
  EXPECT_EQ(h.stretches[0].problem, ScanProblem::kNotConverged);
  EXPECT_EQ(h.stretches[0].first, 4u);
  EXPECT_EQ(h.stretches[0].last, 6u);
  EXPECT_DOUBLE_EQ(h.stretches[0].t_start_s, 100.4);
  EXPECT_DOUBLE_EQ(h.stretches[0].t_end_s, 100.7);
  EXPECT_EQ(h.stretches[0].reason, "no convergence in 12 rebuilds");
  EXPECT_EQ(h.stretches[1].problem, ScanProblem::kDegenerate);
  EXPECT_EQ(h.stretches[1].reason, "unobserved ty rz");
  EXPECT_EQ(FormatStretch(h.stretches[0], 100.0),
            "t 0.40-0.70 s (3 scans): registration failed: no convergence in 12 rebuilds");
  const nlohmann::json j = ScanHealthJson(h);
  EXPECT_EQ(j["not_converged"], 4);
  EXPECT_EQ(j["stretches"].size(), 4u);
  EXPECT_EQ(j["stretches"][1]["problem"], "degenerate");
  EXPECT_EQ(j["stretches"][0]["scans"], 3);
}

TEST(ScanHealth, AHealthyRunHasNoStretches) {
  std::vector<ScanReport> scans = {Scan(0, false, false), Scan(1, true, true), Scan(2, false, false)};
  const ScanHealth h = AssessScanHealth(scans);
  EXPECT_TRUE(h.stretches.empty());
  EXPECT_EQ(h.not_converged + h.degenerate, 0u);
}

}  // namespace
}  // namespace rotolidar::bench
