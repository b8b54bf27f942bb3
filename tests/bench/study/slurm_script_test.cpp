// The Slurm backend without a cluster: the study file's slurm section (errors name the line), the sbatch
// command line, the parsing of scontrol's records, the array task script run by sh with a fake rotolidar, and
// the runner's collection against fake sbatch/scontrol commands (a task killed at its time limit that left no
// record is failed with state TIMEOUT and rerun by the next submission).
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bench/study/process_capture.hpp"
#include "bench/study/slurm_backend.hpp"
#include "bench/study/slurm_script.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

std::string TestDir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/rotolidar_slurm_" + name + "_" + std::to_string(::getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string ReadFile(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

void WriteExecutable(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  ::chmod(path.c_str(), 0755);
}

std::string LoadError(const std::string& text) {
  const std::string path = TestDir("parse") + "/s.yaml";
  std::ofstream(path) << text;
  StudyConfig c;
  const Status s = LoadStudyConfig(path, &c);
  return s ? std::string() : s.message;
}

TEST(StudySlurmConfigTest, SectionParsesAndErrorsNameTheLine) {
  EXPECT_EQ(LoadError("name: x\nslurm:\n  partition: short\n  time_per_point: \"1-02:00:00\"\n  mem_per_point: 2G\n"
                      "  max_parallel: 4\n  sbatch_args: [--account=a]\n"),
            "");
  std::string e = LoadError("name: x\nslurm:\n  time_per_point: soon\n");
  EXPECT_NE(e.find("s.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("slurm.time_per_point"), std::string::npos) << e;
  e = LoadError("name: x\nslurm:\n  mem: 2G\n");
  EXPECT_NE(e.find("s.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("mem"), std::string::npos) << e;
  e = LoadError("name: x\nslurm: {sbatch_args: [account]}\n");
  EXPECT_NE(e.find("slurm.sbatch_args"), std::string::npos) << e;
  e = LoadError("name: x\nrank_by: [ate_rmse_m,\n  no_such_metric]\n");
  EXPECT_NE(e.find("s.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("no_such_metric"), std::string::npos) << e;
}

TEST(SlurmScriptTest, SbatchArgsAndJobId) {
  StudySlurmConfig c;
  c.partition = "short", c.max_parallel = 3, c.sbatch_args = {"--qos=low"};
  const std::vector<std::string> a = SbatchArgs(c, "rotolidar-study-x", 12, "/o/logs", "/o/task.sh");
  const std::vector<std::string> want = {"sbatch", "--parsable", "--job-name=rotolidar-study-x", "--array=0-11%3",
                                         "--output=/o/logs/%A_%a.out", "--time=01:00:00", "--mem=4G",
                                         "--cpus-per-task=1", "--partition=short", "--qos=low", "/o/task.sh"};
  EXPECT_EQ(a, want);
  EXPECT_EQ(ParseSbatchJobId("1234\n"), "1234");
  EXPECT_EQ(ParseSbatchJobId("77;cluster\n"), "77");
  EXPECT_EQ(ParseSbatchJobId("sbatch: error"), "");
  EXPECT_EQ(ShellQuote("a'b c"), "'a'\\''b c'");
}

TEST(SlurmScriptTest, ParsesScontrolRecordsAndExitCodes) {
  const std::string text =  // as `scontrol -o show job 1` prints them (fields shortened)
      "JobId=1 ArrayJobId=1 ArrayTaskId=4-6%2 ArrayTaskThrottle=2 JobName=t JobState=PENDING "
      "Reason=JobArrayTaskLimit ExitCode=0:0 RunTime=00:00:00\n"
      "JobId=3 ArrayJobId=1 ArrayTaskId=1 JobName=t JobState=TIMEOUT Reason=TimeLimit ExitCode=0:15\n"
      "JobId=2 ArrayJobId=1 ArrayTaskId=0 JobName=t JobState=COMPLETED Reason=None ExitCode=0:0\n"
      "JobId=5 ArrayJobId=1 ArrayTaskId=3 JobName=t JobState=FAILED Reason=NonZeroExitCode ExitCode=3:0\n";
  const auto tasks = ParseScontrolJobs(text);
  ASSERT_EQ(tasks.size(), 6u);
  EXPECT_EQ(tasks.at(1).state, "TIMEOUT");
  EXPECT_EQ(tasks.at(1).reason, "TimeLimit");
  EXPECT_EQ(tasks.at(5).state, "PENDING");
  EXPECT_EQ(tasks.count(2), 0u);
  EXPECT_EQ(SlurmExitCode(tasks.at(1).exit_code), 128 + 15);
  EXPECT_EQ(SlurmExitCode(tasks.at(3).exit_code), 3);
  EXPECT_EQ(SlurmExitCode(""), -1);
  EXPECT_TRUE(IsFinalSlurmState("TIMEOUT"));
  EXPECT_TRUE(IsFinalSlurmState("CANCELLED"));
  EXPECT_FALSE(IsFinalSlurmState("RUNNING"));
  EXPECT_FALSE(IsFinalSlurmState("COMPLETING"));
}

TEST(SlurmScriptTest, TaskScriptRunsTheLocalCommandAndRecordsItsStatus) {
  const std::string dir = TestDir("script");
  fs::create_directories(dir + "/out dir/points/p-1"), fs::create_directories(dir + "/out dir/points/p-2");
  WriteExecutable(dir + "/fake rotolidar", "#!/bin/sh\necho \"$@\"\n[ \"$3\" != \"${3%p-2}\" ] && exit 3\nexit 0\n");
  std::ofstream(dir + "/points.txt") << "p-1\np-2\n";
  SlurmTaskScriptSpec spec{dir + "/fake rotolidar", dir + "/slam'cfg.yaml", dir + "/out dir", dir + "/points.txt"};
  WriteExecutable(dir + "/task.sh", SlurmTaskScript(spec));
  for (int task : {0, 1}) {
    CapturedOutput o;
    ASSERT_TRUE(RunCaptured({"env", "SLURM_ARRAY_TASK_ID=" + std::to_string(task), "SLURM_ARRAY_JOB_ID=77",
                             dir + "/task.sh"}, &o));
    EXPECT_EQ(o.exit_code, task == 0 ? 0 : 3) << o.err;
    const std::string p = dir + "/out dir/points/p-" + std::to_string(task + 1);
    EXPECT_EQ(ReadFile(p + "/log.txt"), "demo --out " + p + " --config " + p + "/sim_config.yaml --slam-config " +
                                            dir + "/slam'cfg.yaml\n");
    const nlohmann::json st = nlohmann::json::parse(ReadFile(p + "/slurm_status.json"));
    EXPECT_EQ(st.at("job_id"), "77");
    EXPECT_EQ(st.at("array_task_id"), task);
    EXPECT_EQ(st.at("exit_code"), task == 0 ? 0 : 3);
    EXPECT_GE(st.at("runtime_s").get<double>(), 0.0);
  }
}

/// Fake sbatch (prints job id 42, records its arguments) and scontrol (task 0 COMPLETED, task 1 TIMEOUT).
class FakeSlurmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = TestDir("fake");
    fs::create_directories(dir_ + "/bin");
    WriteExecutable(dir_ + "/bin/sbatch", "#!/bin/sh\necho \"$@\" > '" + dir_ + "/sbatch_args'\necho 42\n");
    WriteExecutable(dir_ + "/bin/scontrol",
                    "#!/bin/sh\necho 'JobId=43 ArrayJobId=42 ArrayTaskId=0 JobState=COMPLETED Reason=None "
                    "ExitCode=0:0'\necho 'JobId=44 ArrayJobId=42 ArrayTaskId=1 JobState=TIMEOUT Reason=TimeLimit "
                    "ExitCode=0:15'\n");
    old_path_ = std::getenv("PATH") ? std::getenv("PATH") : "";
    ::setenv("PATH", (dir_ + "/bin:" + old_path_).c_str(), 1);
  }
  void TearDown() override { ::setenv("PATH", old_path_.c_str(), 1); }
  std::string dir_, old_path_;
};

TEST_F(FakeSlurmTest, TimedOutTaskWithoutRecordIsFailedAndResubmitted) {
  StudyConfig config;
  config.name = "fake";
  config.sweep.seeds = {1, 2};
  SlurmRunOptions o;
  o.out_dir = dir_ + "/out", o.executable = dir_ + "/bin/sbatch", o.slurm.poll_interval_s = 0.05;
  SlurmSubmission sub;
  bool submitted = false;
  ASSERT_TRUE(SubmitSlurmStudy(config, o, &sub, &submitted));
  ASSERT_TRUE(submitted);
  EXPECT_EQ(sub.job_id, "42");
  EXPECT_NE(ReadFile(dir_ + "/sbatch_args").find("--array=0-1 "), std::string::npos);
  // Task 0 finished: it left its record and metrics; task 1 was killed at its time limit and left nothing.
  const std::string p1 = o.out_dir + "/points/seed-1";
  std::ofstream(p1 + "/metrics.json") << "{\"ape_translation_m\": {\"rmse\": 0.5}}";
  std::ofstream(p1 + "/slurm_status.json") << "{\"job_id\": \"42\", \"array_task_id\": 0, \"exit_code\": 0, "
                                              "\"runtime_s\": 7.5}";
  StudyResult r;
  bool stopped = true;
  ASSERT_TRUE(CollectSlurmStudy(config, o, &r, &stopped));
  EXPECT_FALSE(stopped);
  ASSERT_EQ(r.points.size(), 2u);
  EXPECT_EQ(r.points[0].state, PointState::kRan);
  EXPECT_DOUBLE_EQ(r.points[0].runtime_s, 7.5);
  EXPECT_DOUBLE_EQ(r.points[0].metrics[0], 0.5);
  EXPECT_EQ(r.points[1].state, PointState::kFailed);
  EXPECT_EQ(r.points[1].exit_code, 128 + 15);
  EXPECT_NE(r.points[1].message.find("state TIMEOUT"), std::string::npos) << r.points[1].message;
  const nlohmann::json st = nlohmann::json::parse(ReadFile(o.out_dir + "/points/seed-2/point_status.json"));
  EXPECT_EQ(st.at("slurm_state"), "TIMEOUT");
  EXPECT_EQ(st.at("slurm_exit_code"), "0:15");
  EXPECT_EQ(r.ran, 1u);
  EXPECT_EQ(r.failed, 1u);
  // The next submission carries only the failed point.
  ASSERT_TRUE(SubmitSlurmStudy(config, o, &sub, &submitted));
  ASSERT_TRUE(submitted);
  EXPECT_EQ(sub.point_ids, std::vector<std::string>{"seed-2"});
  EXPECT_EQ(ReadFile(sub.dir + "/points.txt"), "seed-2\n");
}

TEST_F(FakeSlurmTest, UncollectedFinishedJobIsCollectedBeforeTheNextSubmission) {
  StudyConfig config;
  config.sweep.seeds = {1, 2};
  SlurmRunOptions o;
  o.out_dir = dir_ + "/out", o.slurm.poll_interval_s = 0.05;
  SlurmSubmission sub;
  bool submitted = false;
  ASSERT_TRUE(SubmitSlurmStudy(config, o, &sub, &submitted));  // then never collected (as after --detach)
  ASSERT_TRUE(SubmitSlurmStudy(config, o, &sub, &submitted));
  ASSERT_TRUE(submitted);
  EXPECT_EQ(sub.point_ids, (std::vector<std::string>{"seed-1", "seed-2"}));  // neither left metrics
  const nlohmann::json st = nlohmann::json::parse(ReadFile(o.out_dir + "/points/seed-2/point_status.json"));
  EXPECT_EQ(st.at("slurm_state"), "TIMEOUT");
  EXPECT_EQ(st.at("state"), "failed");
}

TEST(SlurmBackendTest, MissingSbatchIsAClearError) {
  const char* path = std::getenv("PATH");
  const std::string old = path ? path : "";
  const std::string empty = TestDir("nopath");
  ::setenv("PATH", empty.c_str(), 1);
  StudyConfig config;
  SlurmRunOptions o;
  o.out_dir = empty + "/out";
  SlurmSubmission sub;
  bool submitted = false;
  const Status s = SubmitSlurmStudy(config, o, &sub, &submitted);
  ::setenv("PATH", old.c_str(), 1);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message.find("sbatch not found on PATH"), std::string::npos) << s.message;
}

}  // namespace
}  // namespace rotolidar::bench
