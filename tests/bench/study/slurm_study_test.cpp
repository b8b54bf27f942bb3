// `rotolidar study --backend slurm` against a real one-node Slurm on loopback (slurm_cluster.hpp): the same
// study gives the same results as the local backend (every host-independent value of metrics.json and study.csv,
// and the recordings byte for byte), and a task killed while running is recorded as failed with its Slurm state,
// resubmitted by the next run, and then resumed by the local backend. Skips with the reason when Slurm cannot
// start here; fails instead under CI=true.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bench/study/process_capture.hpp"
#include "bench/study/slurm_script.hpp"
#include "tests/bench/study/slurm_cluster.hpp"
#include "tests/common/test_data.hpp"

#ifndef ROTOLIDAR_EXE
#error "ROTOLIDAR_EXE (the rotolidar binary) must be defined by the build"
#endif

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string ReadFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

double Seconds(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// study.csv without the columns that measure the host (wall times, time per scan, real-time factor).
std::string HostIndependentCsv(const std::string& csv) {
  static const std::set<std::string> host = {"slam_median_scan_ms", "slam_realtime_factor", "sim_wall_s",
                                             "slam_wall_s", "runtime_s"};
  std::istringstream lines(csv);
  std::string line, out;
  std::vector<bool> keep;
  while (std::getline(lines, line)) {
    std::vector<std::string> fields;
    std::istringstream in(line);
    for (std::string f; std::getline(in, f, ',');) fields.push_back(f);
    if (keep.empty())
      for (const std::string& f : fields) keep.push_back(!host.count(f));
    for (size_t i = 0; i < fields.size(); ++i)
      if (i >= keep.size() || keep[i]) out += fields[i] + ",";
    out += "\n";
  }
  return out;
}

/// metrics.json without host-dependent values: keys with wall_time, realtime_factor or a "_ms" suffix.
nlohmann::json HostIndependent(nlohmann::json j) {
  if (!j.is_object()) return j;
  nlohmann::json out = nlohmann::json::object();
  for (auto& [k, v] : j.items()) {
    const bool ms = k.size() > 3 && k.compare(k.size() - 3, 3, "_ms") == 0;
    if (ms || k.find("wall_time") != std::string::npos || k.find("realtime_factor") != std::string::npos) continue;
    out[k] = HostIndependent(v);
  }
  return out;
}

class SlurmStudyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/rotolidar_slurm_" + std::to_string(::getpid());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const auto t0 = Clock::now();
    const std::string why = cluster_.Start(dir_ + "/cluster");
    if (!why.empty()) {
      if (testdata::RunningUnderCi()) FAIL() << "Slurm cannot start (CI=true: not skipping): " << why;
      GTEST_SKIP() << "Slurm cannot start on this machine: " << why;
    }
    std::printf("[timing] loopback Slurm up in %.2f s\n", Seconds(t0));
  }
  void TearDown() override {
    const auto t0 = Clock::now();
    cluster_.Stop();
    std::printf("[timing] loopback Slurm down in %.2f s\n", Seconds(t0));
    if (!HasFailure()) fs::remove_all(dir_);
  }

  /// Writes the study file: the lab's handheld walk, `duration_s` s, seeds 1 and 2.
  std::string WriteStudy(double duration_s) {
    const std::string path = dir_ + "/study.yaml";
    std::ofstream(path) << "name: slurm_loopback\nduration_s: " << duration_s
                        << "\nsim:\n  scene: lab\n  carrier: {type: handheld}\n  camera: {enabled: false}\n"
                           "sweep:\n  seed: [1, 2]\nslurm: {time_per_point: \"00:10:00\", mem_per_point: 500M, "
                           "poll_interval_s: 0.2}\n";
    return path;
  }

  /// `rotolidar study ARGS...`; its stdout + stderr in *log.
  int Study(const std::vector<std::string>& args, std::string* log) {
    std::vector<std::string> argv = {ROTOLIDAR_EXE, "study"};
    argv.insert(argv.end(), args.begin(), args.end());
    CapturedOutput o;
    const Status s = RunCaptured(argv, &o);
    *log = s ? o.out + o.err : s.message;
    return o.exit_code;
  }

  std::string dir_;
  testing_slurm::LoopbackSlurm cluster_;
};

TEST_F(SlurmStudyTest, SameResultsAsLocalBackend) {
  const std::string study = WriteStudy(2.0), local = dir_ + "/local", slurm = dir_ + "/slurm";
  std::string log;
  ASSERT_EQ(Study({study, "--out", local, "--backend", "local", "--jobs", "2"}, &log), 0) << log;
  const auto t0 = Clock::now();
  ASSERT_EQ(Study({study, "--out", slurm, "--backend", "slurm"}, &log), 0) << log;
  std::printf("[timing] 2-point study through Slurm: %.2f s\n", Seconds(t0));
  EXPECT_NE(log.find("submitted slurm job"), std::string::npos) << log;
  EXPECT_EQ(HostIndependentCsv(ReadFile(slurm + "/study.csv")), HostIndependentCsv(ReadFile(local + "/study.csv")));
  for (const char* id : {"seed-1", "seed-2"}) {
    SCOPED_TRACE(id);
    const std::string l = local + "/points/" + id, s = slurm + "/points/" + id;
    const nlohmann::json lm = HostIndependent(nlohmann::json::parse(ReadFile(l + "/metrics.json")));
    EXPECT_FALSE(lm.empty());
    EXPECT_EQ(HostIndependent(nlohmann::json::parse(ReadFile(s + "/metrics.json"))), lm);
    for (const char* f : {"sim_config.yaml", "recording/lidar.pcap", "recording/imu.csv", "recording/encoder.csv",
                          "slam/trajectory.tum", "slam/map.pcd"})
      EXPECT_TRUE(ReadFile(l + "/" + f) == ReadFile(s + "/" + f) && !ReadFile(l + "/" + f).empty()) << f;
    const nlohmann::json st = nlohmann::json::parse(ReadFile(s + "/point_status.json"));
    EXPECT_EQ(st.value("backend", ""), "slurm");
    EXPECT_EQ(st.value("slurm_state", ""), "COMPLETED");
    EXPECT_EQ(st.value("state", ""), "ran");
  }
  const std::string jobcomp = ReadFile(cluster_.jobcomp_path());
  EXPECT_NE(jobcomp.find("JobState=COMPLETED"), std::string::npos) << jobcomp;
}

/// Polls scontrol until array task `task` of `job` runs; false after timeout_s.
bool WaitRunning(const std::string& job, size_t task, double timeout_s) {
  const auto t0 = Clock::now();
  while (Seconds(t0) < timeout_s) {
    CapturedOutput o;
    if (RunCaptured({"scontrol", "-o", "show", "job", job}, &o) && o.exit_code == 0) {
      const auto tasks = ParseScontrolJobs(o.out);
      if (tasks.count(task) && tasks.at(task).state == "RUNNING") return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

TEST_F(SlurmStudyTest, KilledTaskIsRecordedAndRerun) {
  const std::string study = WriteStudy(5.0), out = dir_ + "/out";
  std::string log;
  ASSERT_EQ(Study({study, "--out", out, "--backend", "slurm", "--detach"}, &log), 0) << log;
  const nlohmann::json job = nlohmann::json::parse(ReadFile(out + "/slurm/job.json"));
  const std::string id = job.at("job_id").get<std::string>();
  ASSERT_EQ(job.at("points"), nlohmann::json({"seed-1", "seed-2"}));
  ASSERT_TRUE(WaitRunning(id, 1, 60.0)) << "array task 1 never ran";
  CapturedOutput o;
  ASSERT_TRUE(RunCaptured({"scancel", id + "_1"}, &o) && o.exit_code == 0) << o.err;

  // Collect: exit 1 (a point failed); the killed point is failed with its Slurm state, the other ran.
  EXPECT_EQ(Study({study, "--out", out, "--collect"}, &log), 1) << log;
  const std::string csv = ReadFile(out + "/study.csv");
  EXPECT_NE(csv.find("\nseed-1,ran,0,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\nseed-2,failed,"), std::string::npos) << csv;
  const nlohmann::json st = nlohmann::json::parse(ReadFile(out + "/points/seed-2/point_status.json"));
  EXPECT_EQ(st.value("slurm_state", ""), "CANCELLED") << st.dump();
  EXPECT_NE(st.value("exit_code", 0), 0) << st.dump();
  EXPECT_FALSE(fs::exists(out + "/points/seed-2/metrics.json"));
  EXPECT_NE(ReadFile(out + "/study.html").find("state CANCELLED"), std::string::npos);
  EXPECT_NE(ReadFile(cluster_.jobcomp_path()).find("JobState=CANCELLED"), std::string::npos);

  // The next Slurm run submits only the failed point; then the local backend finds nothing left to run.
  ASSERT_EQ(Study({study, "--out", out, "--backend", "slurm"}, &log), 0) << log;
  const nlohmann::json rerun = nlohmann::json::parse(ReadFile(out + "/slurm/job.json"));
  EXPECT_NE(rerun.at("job_id"), job.at("job_id"));
  EXPECT_EQ(rerun.at("points"), nlohmann::json({"seed-2"}));
  const std::string csv2 = ReadFile(out + "/study.csv");
  EXPECT_NE(csv2.find("\nseed-1,resumed,0,"), std::string::npos) << csv2;
  EXPECT_NE(csv2.find("\nseed-2,ran,0,"), std::string::npos) << csv2;
  ASSERT_EQ(Study({study, "--out", out, "--backend", "local", "--jobs", "1"}, &log), 0) << log;
  EXPECT_NE(log.find("2 finished earlier, 0 to run"), std::string::npos) << log;
}

}  // namespace
}  // namespace rotolidar::bench
