// The deskew error of a run reaches the study table: EvaluateRun scores the scans that kept their deskewed
// points (every deskew_scan_stride-th), the demo's metrics.json writer puts the summary under deskew_error_m,
// the study's reader takes deskew_median_m from it, and the report's headline shows it. The run is synthetic:
// the truth is analytic and each deskewed point is its true position plus a known offset, so every statistic
// is known exactly. Also the subsampling rule (DeskewScanStride) and that a run without deskew data writes none.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bench/demo/demo.hpp"
#include "bench/report/run_report.hpp"
#include "bench/study/study_config.hpp"
#include "bench/study/study_runner.hpp"
#include "core/io/trajectory_io.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

constexpr int kScans = 10;
constexpr int kPointsPerScan = 100;  // errors 1, 2, ..., 100 mm, plus one point left NaN (not deskewed)

/// Base: 0.5 m/s along x, turning to y at t = 1 s (an L, so the APE's alignment is defined), no rotation. LiDAR:
/// 0.2 m above the base, turning about z at 3 rad/s. Both are exact under the metric's interpolation between
/// 10 ms samples (linear translation with the corner on a sample, slerp about a fixed axis).
Eigen::Vector3d BasePosition(double t) {
  return t <= 1.0 ? Eigen::Vector3d(0.5 * t, 0.1, 1.0) : Eigen::Vector3d(0.5, 0.1 + 0.5 * (t - 1.0), 1.0);
}
Pose3 TrueBase(double t) { return MakePose(BasePosition(t), Eigen::Quaterniond::Identity()); }
Pose3 TrueLidar(double t) {
  return MakePose(BasePosition(t) + Eigen::Vector3d(0.0, 0.0, 0.2),
                  Eigen::Quaterniond(Eigen::AngleAxisd(3.0 * t, Eigen::Vector3d::UnitZ())));
}
double ScanStart(int i) { return 0.2 + 0.1 * i; }

struct DeskewRun {
  std::string dir, recording, slam_dir;
  SlamRunResult slam;
};

/// Truth over [0, 2] s; kScans reports, of which only those with i % stride == 0 carry deskew data (as RunSlam
/// leaves them). Point j of a scan is deskewed (j + 1) mm off its true position; the last point is NaN.
DeskewRun MakeDeskewRun(const std::string& name, size_t stride) {
  DeskewRun run;
  run.dir = ::testing::TempDir() + "/rotolidar_deskew_metrics_" + name + "_" + std::to_string(::getpid());
  fs::remove_all(run.dir);
  run.recording = run.dir + "/recording", run.slam_dir = run.dir + "/slam";
  fs::create_directories(run.recording + "/truth");
  fs::create_directories(run.slam_dir);
  Trajectory base, lidar;
  for (int k = 0; k <= 200; ++k) {
    base.push_back({0.01 * k, TrueBase(0.01 * k)});
    lidar.push_back({0.01 * k, TrueLidar(0.01 * k)});
  }
  EXPECT_TRUE(WriteTrajectory(run.recording + "/truth/base.tum", TrajectoryFormat::kTum, base).ok);
  EXPECT_TRUE(WriteTrajectory(run.recording + "/truth/lidar.tum", TrajectoryFormat::kTum, lidar).ok);
  const Eigen::Vector3d offset_dir = Eigen::Vector3d(1.0, 2.0, 2.0) / 3.0;
  for (int i = 0; i < kScans; ++i) {
    ScanReport r;
    r.t_start_s = ScanStart(i), r.t_end_s = r.t_start_s + 0.1;
    r.num_points = kPointsPerScan + 1;
    run.slam.trajectory.push_back({r.t_start_s, TrueBase(r.t_start_s)});  // SLAM world = truth world
    if (stride > 0 && i % stride == 0) {
      for (int j = 0; j <= kPointsPerScan; ++j) {
        LidarPoint p;
        p.x_m = 3.0f, p.y_m = 0.01f * j, p.z_m = 0.5f;
        p.t_s = r.t_start_s + 0.0009 * j;
        const Eigen::Vector3d p_true =
            TrueBase(r.t_start_s).inverse() * (TrueLidar(p.t_s) * Eigen::Vector3d(p.x_m, p.y_m, p.z_m));
        r.deskew_source.push_back(p);
        const Eigen::Vector3f deskewed = (p_true + 0.001 * (j + 1) * offset_dir).cast<float>();
        r.deskewed_base.push_back(j == kPointsPerScan ? Eigen::Vector3f::Constant(NAN) : deskewed);
      }
    }
    run.slam.scans.push_back(r);
  }
  run.slam.deskew_scan_stride = stride;
  run.slam.data_duration_s = 1.0, run.slam.wall_time_s = 0.5;
  return run;
}

/// EvaluateRun, then the demo's metrics.json writer; returns the parsed file.
nlohmann::json EvaluateAndWrite(const DeskewRun& run, DemoResult* result) {
  result->slam = run.slam;
  RunEvaluationOptions options;
  options.map_metrics = false;
  const Status s = EvaluateRun(run.recording, run.slam_dir, run.slam, "", options, &result->evaluation);
  EXPECT_TRUE(s.ok) << s.message;
  EXPECT_TRUE(result->evaluation.has_truth) << result->evaluation.truth_note;
  DemoOptions demo;
  demo.out_dir = run.dir;
  EXPECT_TRUE(WriteDemoMetrics(run.dir + "/metrics.json", demo, *result).ok);
  std::ifstream in(run.dir + "/metrics.json");
  return nlohmann::json::parse(in, nullptr, false);
}

double StudyValue(const std::string& metrics_json, const std::string& metric) {
  std::vector<double> values;
  EXPECT_TRUE(ReadPointMetrics(metrics_json, &values).ok);
  for (size_t i = 0; i < StudyMetrics().size(); ++i)
    if (StudyMetrics()[i].name == metric) return values.at(i);
  ADD_FAILURE() << metric;
  return NAN;
}

TEST(DeskewMetrics, ReachesMetricsJsonTheStudyTableAndTheHeadline) {
  const DeskewRun run = MakeDeskewRun("stride2", 2);
  DemoResult result;
  const nlohmann::json j = EvaluateAndWrite(run, &result);
  const RunEvaluation& ev = result.evaluation;
  ASSERT_TRUE(ev.has_deskew) << ev.deskew_note;
  // Scans 0, 2, 4, 6, 8 scored, 100 points each: the errors 1..100 mm five times over. Median of 500 = mean of
  // the 250th and 251st (50 and 51 mm); p90 = the 450th (90 mm); max 100 mm. Odd scans hold no data and are
  // skipped (scoring them would fail: "no deskew data"); one NaN point per scored scan is counted.
  EXPECT_EQ(ev.deskew.all.count, 500u);
  EXPECT_EQ(ev.deskew.per_scan.size(), 5u);
  EXPECT_EQ(ev.deskew.num_not_deskewed, 5u);
  EXPECT_EQ(ev.deskew.num_outside_truth, 0u);
  EXPECT_NEAR(ev.deskew.all.median_m, 0.0505, 1e-5);
  EXPECT_NEAR(ev.deskew.all.p90_m, 0.090, 1e-5);
  EXPECT_NEAR(ev.deskew.all.max_m, 0.100, 1e-5);

  ASSERT_TRUE(j.is_object());
  ASSERT_TRUE(j.contains("deskew_error_m"));
  const nlohmann::json& d = j["deskew_error_m"];
  EXPECT_EQ(d["points"].get<size_t>(), 500u);
  EXPECT_EQ(d["scans"].get<size_t>(), 5u);
  EXPECT_EQ(d["scan_stride"].get<size_t>(), 2u);
  EXPECT_EQ(d["not_deskewed"].get<size_t>(), 5u);
  for (const char* key : {"median", "p90", "p95", "rmse", "mean", "max"}) EXPECT_TRUE(d.contains(key)) << key;
  EXPECT_DOUBLE_EQ(d["median"].get<double>(), ev.deskew.all.median_m);
  EXPECT_DOUBLE_EQ(d["p90"].get<double>(), ev.deskew.all.p90_m);
  // The study's reader takes the column from this file: the deskew plot has data.
  EXPECT_NEAR(StudyValue(run.dir + "/metrics.json", "deskew_median_m"), 0.0505, 1e-5);

  RunReportInput in;
  in.title = "deskew";
  in.slam = &result.slam;
  in.evaluation = &ev;
  const std::string html = RenderRunReport(in);
  EXPECT_NE(html.find("deskew error median / p90 per point"), std::string::npos);
  EXPECT_NE(html.find("0.0505 / 0.0900 m (500 points, 1 scan in 2)"), std::string::npos);
}

TEST(DeskewMetrics, RunWithoutDeskewDataWritesNone) {
  const DeskewRun run = MakeDeskewRun("none", 0);  // keep_deskewed off: no scan holds points
  DemoResult result;
  const nlohmann::json j = EvaluateAndWrite(run, &result);
  EXPECT_FALSE(result.evaluation.has_deskew);
  EXPECT_NE(result.evaluation.deskew_note.find("keep_deskewed"), std::string::npos)
      << result.evaluation.deskew_note;
  ASSERT_TRUE(j.is_object());
  EXPECT_TRUE(j.contains("ape_translation_m"));
  EXPECT_FALSE(j.contains("deskew_error_m"));
  EXPECT_TRUE(std::isnan(StudyValue(run.dir + "/metrics.json", "deskew_median_m")));  // an empty field, not 0
}

TEST(DeskewMetrics, StrideKeepsAbout20SecondsAndReleaseFreesThePoints) {
  EXPECT_EQ(DeskewScanStride(0.0), 1u);
  EXPECT_EQ(DeskewScanStride(20.0), 1u);  // a 20 s run keeps every scan (~5.7 M points)
  EXPECT_EQ(DeskewScanStride(20.5), 2u);
  EXPECT_EQ(DeskewScanStride(60.0), 3u);
  EXPECT_EQ(DeskewScanStride(600.0), 30u);
  EXPECT_EQ(DeskewScanStride(NAN), 1u);
  DeskewRun run = MakeDeskewRun("release", 1);
  ReleaseDeskewData(&run.slam);
  EXPECT_EQ(run.slam.deskew_scan_stride, 0u);
  for (const ScanReport& r : run.slam.scans) EXPECT_TRUE(r.deskew_source.empty() && r.deskewed_base.empty());
}

}  // namespace
}  // namespace rotolidar::bench
