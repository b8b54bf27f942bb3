// Trade studies: study YAML errors name file:line, the sweep expands to the full factorial, a rerun skips
// finished points, failed points are recorded, and the default runner really spawns a process and captures
// its log. The runners here are fakes (a function or a shell script): no simulation runs.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

#include <gtest/gtest.h>

#include "bench/study/study_config.hpp"
#include "bench/study/study_report.hpp"
#include "bench/study/study_runner.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

std::string TestDir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/rotolidar_study_" + name + "_" + std::to_string(::getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string WriteFile(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

std::string ReadFile(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// Loads `text` as a study file; returns the error message ("" on success).
std::string LoadError(const std::string& text, StudyConfig* config = nullptr) {
  const std::string path = WriteFile(TestDir("parse") + "/s.yaml", text);
  StudyConfig c;
  const Status s = LoadStudyConfig(path, config ? config : &c);
  return s ? std::string() : s.message;
}

TEST(StudyConfigTest, ErrorsNameFileAndLine) {
  // Unknown top-level key on line 3.
  std::string e = LoadError("name: x\nduration_s: 5\nbogus: 1\n");
  EXPECT_NE(e.find("s.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("bogus"), std::string::npos) << e;
  // Unknown sweep axis on line 3.
  e = LoadError("sweep:\n  seed: [1, 2]\n  speeds: [1]\n");
  EXPECT_NE(e.find("s.yaml:3"), std::string::npos) << e;
  // Unknown key inside a variant's sim config (line 4): the study file's line, from the sim parser.
  e = LoadError("sweep:\n  variant:\n    fixed:\n      motor: {profile: {typo: 1}}\n");
  EXPECT_NE(e.find("s.yaml:4"), std::string::npos) << e;
  EXPECT_NE(e.find("typo"), std::string::npos) << e;
  // Unknown key in the inline base sim config (line 2).
  e = LoadError("sim:\n  scen: box_room\n");
  EXPECT_NE(e.find("s.yaml:2"), std::string::npos) << e;
  // Unknown profile name (line 2).
  e = LoadError("sweep:\n  profile: [constant, spinning]\n");
  EXPECT_NE(e.find("s.yaml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("spinning"), std::string::npos) << e;
  // Unknown plot metric (line 4) and a wrong value type (line 2).
  e = LoadError("sweep:\n  motor_speed_radps: [1, 2]\nplots:\n  - ate_rmse\n");
  EXPECT_NE(e.find("s.yaml:4"), std::string::npos) << e;
  e = LoadError("sweep:\n  seed: [1, two]\n");
  EXPECT_NE(e.find("s.yaml:2"), std::string::npos) << e;
  // A line plot against an axis that is not swept is rejected by Validate.
  e = LoadError("plots:\n  - {kind: line, metric: ate_rmse_m, x: motor_speed_radps}\n");
  EXPECT_NE(e.find("must be a swept axis"), std::string::npos) << e;
}

TEST(StudyConfigTest, ParsesBaseVariantsAxesAndPlots) {
  StudyConfig c;
  ASSERT_EQ(LoadError("name: t\nsim: {scene: corridor, seed: 7}\nduration_s: 12\n"
                      "sweep:\n"
                      "  variant:\n"
                      "    fixed: {motor: {profile: {type: constant, speed_radps: 0.0, theta0_rad: 1.5}}}\n"
                      "    rotating: {}\n"
                      "  motor_speed_radps: [1.3, 2.6]\n"
                      "  axis: [horizontal, vertical]\n"
                      "plots:\n  - coverage_total\n  - {kind: bars, metrics: [coverage_total, completeness_total]}\n",
                      &c),
            "");
  EXPECT_EQ(c.name, "t");
  EXPECT_EQ(c.base.scene, "corridor");
  EXPECT_EQ(c.base.seed, 7u);
  EXPECT_EQ(c.base.duration_s, 12.0);
  ASSERT_EQ(c.sweep.variants.size(), 2u);
  EXPECT_EQ(c.sweep.variants[0].name, "fixed");  // document order kept
  EXPECT_EQ(c.sweep.variants[0].sim.motor.profile.theta0_rad, 1.5);
  EXPECT_EQ(c.sweep.variants[0].sim.scene, "corridor");  // variants start from the base
  EXPECT_EQ(c.sweep.variants[0].sim.duration_s, 12.0);
  EXPECT_EQ(c.sweep.NumPoints(), 2u * 2u * 2u);
  ASSERT_EQ(c.plots.size(), 2u);
  EXPECT_EQ(c.plots[0].kind, StudyPlotKind::kLine);
  EXPECT_EQ(c.plots[1].kind, StudyPlotKind::kBars);
  EXPECT_EQ(c.plots[1].metrics.size(), 2u);
}

StudyConfig SpeedProfileSeedStudy() {
  StudyConfig c;
  c.sweep.motor_speed_radps = {1.0, 2.0, 3.0};
  c.sweep.profiles = {sim::MotorProfileType::kConstant, sim::MotorProfileType::kNodding};
  c.sweep.seeds = {1, 2};
  return c;
}

TEST(StudyRunnerTest, ExpandsTheFullFactorial) {
  StudyConfig c = SpeedProfileSeedStudy();
  c.sweep.variants = {{"a", c.base}, {"b", c.base}};
  c.sweep.variants[1].sim.scene = "corridor";
  std::vector<StudyPoint> points;
  ASSERT_TRUE(ExpandStudy(c, &points));
  ASSERT_EQ(points.size(), 2u * 3u * 2u * 2u);
  std::set<std::string> ids;
  std::set<std::tuple<std::string, int, double, uint64_t>> combos;
  for (const StudyPoint& p : points) {
    ids.insert(p.id);
    combos.insert({p.variant, int(p.sim.motor.profile.type), p.sim.motor.profile.speed_radps, p.sim.seed});
    EXPECT_EQ(p.sim.scene, p.variant == "b" ? "corridor" : "box_room");  // the variant's config carried along
  }
  EXPECT_EQ(ids.size(), points.size());     // one folder per point
  EXPECT_EQ(combos.size(), points.size());  // every combination exactly once
  // Expansion order: variant outermost, then profile, speed, seed fastest.
  EXPECT_EQ(points[0].id, "variant-a__profile-constant__speed-1__seed-1");
  EXPECT_EQ(points[1].id, "variant-a__profile-constant__speed-1__seed-2");
  EXPECT_EQ(points[2].id, "variant-a__profile-constant__speed-2__seed-1");
  EXPECT_EQ(points.back().id, "variant-b__profile-nodding__speed-3__seed-2");
  EXPECT_EQ(points[2].sim.motor.profile.speed_radps, 2.0);

  StudyConfig none;  // nothing swept: one point, the base config
  ASSERT_TRUE(ExpandStudy(none, &points));
  ASSERT_EQ(points.size(), 1u);
  EXPECT_EQ(points[0].id, "base");

  StudyConfig bad;  // stop_and_go needs a move speed: the expansion names the point
  bad.sweep.profiles = {sim::MotorProfileType::kStopAndGo};
  bad.sweep.motor_speed_radps = {0.0, 1.0};
  const Status s = ExpandStudy(bad, &points);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message.find("profile-stop_and_go__speed-0"), std::string::npos) << s.message;
}

/// A fake point runner: counts calls per point and writes a metrics.json whose ATE is the motor speed, except
/// for the points in `fail`, which exit 3 without metrics.
struct FakeRunner {
  std::mutex mutex;
  std::vector<std::string> calls;
  std::set<std::string> fail;

  PointRunner Runner() {
    return [this](const StudyPoint& p, const std::string& dir) -> PointRunOutcome {
      {
        std::lock_guard<std::mutex> lock(mutex);
        calls.push_back(p.id);
        if (fail.count(p.id)) return {3, "exit status 3"};
      }
      EXPECT_TRUE(fs::exists(dir + "/sim_config.yaml"));  // written before the run
      std::ostringstream json;
      json << "{\"ape_translation_m\": {\"rmse\": " << p.sim.motor.profile.speed_radps << "},"
           << " \"map\": {\"coverage\": {\"total\": {\"coverage\": 0.5}}}}";
      if (!WriteFileAtomically(dir + "/metrics.json", json.str())) return {1, "write failed"};
      return {0, ""};
    };
  }
};

size_t Index(const std::string& metric) {
  for (size_t i = 0; i < StudyMetrics().size(); ++i)
    if (StudyMetrics()[i].name == metric) return i;
  ADD_FAILURE() << metric;
  return 0;
}

TEST(StudyRunnerTest, ResumeSkipsFinishedPointsAndRecordsFailures) {
  const StudyConfig c = SpeedProfileSeedStudy();  // 12 points
  StudyRunOptions o;
  o.out_dir = TestDir("resume");
  o.jobs = 3;
  std::vector<std::string> lines;
  o.progress = [&lines](const std::string& l) { lines.push_back(l); };
  std::vector<StudyPoint> points;
  ASSERT_TRUE(ExpandStudy(c, &points));

  // Pre-create one finished point: its config and a metrics.json, as an interrupted earlier run left them.
  const StudyPoint& done = points[4];
  fs::create_directories(o.out_dir + "/points/" + done.id);
  WriteFile(o.out_dir + "/points/" + done.id + "/sim_config.yaml", PointConfigText(done));
  WriteFile(o.out_dir + "/points/" + done.id + "/metrics.json",
            "{\"ape_translation_m\": {\"rmse\": 42.0}, \"deskew_error_m\": {\"median\": 0.02},"
            " \"dynamic\": {\"share_of_seen\": 0.031}}");
  // And one interrupted mid-write: not JSON, so not finished.
  const StudyPoint& torn = points[5];
  fs::create_directories(o.out_dir + "/points/" + torn.id);
  WriteFile(o.out_dir + "/points/" + torn.id + "/sim_config.yaml", PointConfigText(torn));
  WriteFile(o.out_dir + "/points/" + torn.id + "/metrics.json", "{\"ape_translation_m\": {\"rm");

  FakeRunner fake;
  fake.fail = {points[7].id};
  StudyResult r;
  ASSERT_TRUE(RunStudy(c, o, fake.Runner(), &r));
  EXPECT_EQ(fake.calls.size(), 11u);
  EXPECT_EQ(std::count(fake.calls.begin(), fake.calls.end(), done.id), 0);
  EXPECT_EQ(std::count(fake.calls.begin(), fake.calls.end(), torn.id), 1);
  EXPECT_EQ(r.ran, 10u);
  EXPECT_EQ(r.resumed, 1u);
  EXPECT_EQ(r.failed, 1u);
  EXPECT_EQ(r.points[4].state, PointState::kResumed);
  EXPECT_EQ(r.points[4].metrics[Index("ate_rmse_m")], 42.0);  // the earlier result, not recomputed
  EXPECT_EQ(r.points[4].metrics[Index("deskew_median_m")], 0.02);  // a nested metric (demo's deskew_error_m)
  EXPECT_EQ(r.points[4].metrics[Index("dynamic_share")], 0.031);  // the dense map's share of moving objects
  EXPECT_EQ(r.points[7].state, PointState::kFailed);
  EXPECT_EQ(r.points[7].exit_code, 3);
  EXPECT_TRUE(std::isnan(r.points[7].metrics[Index("ate_rmse_m")]));
  EXPECT_EQ(r.points[0].metrics[Index("ate_rmse_m")], 1.0);
  EXPECT_TRUE(std::isnan(r.points[0].metrics[Index("deskew_median_m")]));  // absent from metrics.json
  EXPECT_TRUE(std::isfinite(r.points[0].metrics[Index("runtime_s")]));
  EXPECT_EQ(lines.back(), "[study] 12/12 points done");

  // The table: one row per point, the failed one marked with its exit status and empty metrics.
  const std::string csv = StudyCsv(r);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 13);
  std::istringstream rows(csv);
  std::string header, row;
  std::getline(rows, header);
  EXPECT_EQ(header.rfind("point,state,exit_code,variant,scene,carrier,axis,profile,motor_speed_radps,seed,", 0), 0u);
  for (int i = 0; i <= 7; ++i) std::getline(rows, row);
  EXPECT_EQ(row.rfind(points[7].id + ",failed,3,", 0), 0u) << row;
  EXPECT_NE(row.find(",,,"), std::string::npos) << row;  // missing metrics are empty fields

  // Second run: only the failed point runs again.
  fake.calls.clear();
  fake.fail.clear();
  ASSERT_TRUE(RunStudy(c, o, fake.Runner(), &r));
  ASSERT_EQ(fake.calls.size(), 1u);
  EXPECT_EQ(fake.calls[0], points[7].id);
  EXPECT_EQ(r.resumed, 11u);
  EXPECT_EQ(r.ran, 1u);

  // A changed study (another duration) changes every point's config: all rerun.
  StudyConfig longer = c;
  longer.base.duration_s = 30.0;
  fake.calls.clear();
  ASSERT_TRUE(RunStudy(longer, o, fake.Runner(), &r));
  EXPECT_EQ(fake.calls.size(), 12u);

  ASSERT_TRUE(WriteStudyOutputs(c, r, o.out_dir));
  EXPECT_TRUE(fs::exists(o.out_dir + "/study.csv"));
  const std::string html = ReadFile(o.out_dir + "/study.html");
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find(points[7].id), std::string::npos);
  EXPECT_EQ(StudyFigures(c, r).size(), 4u);  // the default plots: coverage, ATE, deskew, runtime vs speed
}

/// A stand-in for the rotolidar executable: a shell script that reads `demo --out DIR --config CFG`.
std::string FakeExecutable(const std::string& dir, const std::string& body) {
  const std::string path = WriteFile(dir + "/fake_rotolidar.sh", "#!/bin/sh\n" + body);
  ::chmod(path.c_str(), 0755);
  return path;
}

TEST(StudyRunnerTest, DefaultRunnerSpawnsAProcessAndCapturesItsLog) {
  const std::string dir = TestDir("spawn");
  StudyConfig c;
  c.sweep.seeds = {1, 2, 3};
  // Seed 1 succeeds, seed 2 crashes on a signal, seed 3 exits 5: the sweep survives all three.
  const std::string exe = FakeExecutable(
      dir, "echo \"args: $*\"\necho oops >&2\n"
           "case \"$3\" in\n"
           "  *seed-1) printf '{\"slam\": {\"realtime_factor\": 2.5}}' > \"$3/metrics.json\";;\n"
           "  *seed-2) kill -SEGV $$;;\n"
           "  *) exit 5;;\n"
           "esac\n");
  StudyRunOptions o;
  o.out_dir = dir + "/out";
  o.jobs = 2;
  StudyResult r;
  ASSERT_TRUE(RunStudy(c, o, MakeDemoProcessRunner(exe, "slam.yaml"), &r));
  ASSERT_EQ(r.points.size(), 3u);
  EXPECT_EQ(r.points[0].state, PointState::kRan);
  EXPECT_EQ(r.points[0].metrics[Index("slam_realtime_factor")], 2.5);
  EXPECT_EQ(r.points[1].state, PointState::kFailed);
  EXPECT_EQ(r.points[1].exit_code, 128 + SIGSEGV);
  EXPECT_EQ(r.points[2].state, PointState::kFailed);
  EXPECT_EQ(r.points[2].exit_code, 5);
  const std::string pdir = o.out_dir + "/points/" + r.points[0].point.id;
  const std::string log = ReadFile(pdir + "/log.txt");
  EXPECT_NE(log.find("args: demo --out " + pdir + " --config " + pdir + "/sim_config.yaml --slam-config slam.yaml"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("oops"), std::string::npos) << log;  // stderr captured too
  EXPECT_NE(ReadFile(o.out_dir + "/points/" + r.points[2].point.id + "/point_status.json").find("\"exit_code\": 5"),
            std::string::npos);

  // An executable that does not exist: every point fails with exit code -1, nothing throws.
  const std::string missing_out = dir + "/missing";
  o.out_dir = missing_out;
  ASSERT_TRUE(RunStudy(c, o, MakeDemoProcessRunner(dir + "/no_such_binary", ""), &r));
  EXPECT_EQ(r.failed, 3u);
  EXPECT_NE(r.points[0].exit_code, 0);
}

}  // namespace
}  // namespace rotolidar::bench
