#include "bench/study/slurm_backend.hpp"

#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "bench/study/process_capture.hpp"
#include "bench/study/slurm_script.hpp"

namespace rotolidar::bench {
namespace fs = std::filesystem;
namespace {

using TaskMap = std::map<size_t, SlurmTaskRecord>;

std::string ReadText(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return f ? ss.str() : std::string();
}

std::string JobJsonPath(const std::string& out_dir) { return out_dir + "/slurm/job.json"; }

Status WriteSubmission(const std::string& out_dir, const SlurmSubmission& s) {
  const nlohmann::json j = {{"job_id", s.job_id}, {"dir", s.dir}, {"points", s.point_ids},
                            {"collected", s.collected}};
  return WriteFileAtomically(JobJsonPath(out_dir), j.dump(2) + "\n");
}

/// scontrol's view of the job: *known = false when Slurm no longer (or never) knew it.
Status QueryJob(const std::string& job_id, TaskMap* tasks, bool* known) {
  CapturedOutput o;
  if (Status s = RunCaptured({"scontrol", "-o", "show", "job", job_id}, &o); !s)
    return Status::Error(s.message + " (the Slurm backend needs Slurm's client commands)");
  *known = o.exit_code == 0;
  if (o.exit_code != 0) {
    if (o.err.find("Invalid job id") != std::string::npos) return Status::Ok();
    return Status::Error("scontrol show job " + job_id + " failed (exit " + std::to_string(o.exit_code) +
                         "): " + o.err);
  }
  *tasks = ParseScontrolJobs(o.out);
  return Status::Ok();
}

std::string OwnExecutable(const std::string& executable) {
  if (!executable.empty()) return fs::absolute(executable).string();
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? "/proc/self/exe" : exe.string();
}

/// out_dir/slurm/submit_<k> for the first k not used yet.
std::string NextSubmitDir(const std::string& slurm_dir) {
  for (int k = 1;; ++k) {
    const std::string dir = slurm_dir + "/submit_" + std::to_string(k);
    if (!fs::exists(dir)) return dir;
  }
}

/// Writes points.txt, task.sh and logs/ into sub->dir for the given point ids.
Status WriteSubmitFiles(const std::string& abs_out, const std::string& slam_config, const std::string& exe,
                        SlurmSubmission* sub) {
  std::error_code ec;
  fs::create_directories(sub->dir + "/logs", ec);
  if (ec) return Status::Error(sub->dir + "/logs: cannot create: " + ec.message());
  std::string points;
  for (const std::string& id : sub->point_ids) points += id + "\n";
  if (Status s = WriteFileAtomically(sub->dir + "/points.txt", points); !s) return s;
  SlurmTaskScriptSpec spec{exe, slam_config.empty() ? "" : fs::absolute(slam_config).string(), abs_out,
                           sub->dir + "/points.txt"};
  const std::string script = sub->dir + "/task.sh";
  if (Status s = WriteFileAtomically(script, SlurmTaskScript(spec)); !s) return s;
  if (::chmod(script.c_str(), 0755) != 0) return Status::Error(script + ": chmod failed");
  return Status::Ok();
}

/// "2 pending, 1 running, 3 finished (1 failed) of 6".
std::string Counts(const TaskMap& tasks, size_t total) {
  size_t pending = 0, running = 0, finished = 0, failed = 0;
  for (const auto& [k, r] : tasks) {
    if (IsFinalSlurmState(r.state)) ++finished, failed += r.state != "COMPLETED";
    else if (r.state == "PENDING") ++pending;
    else ++running;
  }
  std::ostringstream os;
  os << pending << " pending, " << running << " running, " << finished << " finished (" << failed << " failed) of "
     << total;
  return os.str();
}

/// Polls scontrol until every task is final or Slurm forgets the job; *seen keeps each task's last record.
Status WaitForJob(const SlurmSubmission& sub, const SlurmRunOptions& options, TaskMap* seen, bool* stopped) {
  *stopped = false;
  std::string last_line;
  for (;;) {
    TaskMap now;
    bool known = false;
    if (Status s = QueryJob(sub.job_id, &now, &known); !s) return s;
    for (auto& [k, r] : now) (*seen)[k] = r;
    bool active = false;
    for (const auto& [k, r] : now) active |= !IsFinalSlurmState(r.state);
    const std::string line = "[study] slurm job " + sub.job_id + ": " + Counts(*seen, sub.point_ids.size());
    if (line != last_line && options.progress) options.progress(line);
    last_line = line;
    if (!known || !active) return Status::Ok();
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.slurm.poll_interval_s);
    while (std::chrono::steady_clock::now() < until) {
      if (options.stop && *options.stop) return *stopped = true, Status::Ok();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
}

/// The row of a submitted point from its folder, the task's own record and Slurm's last word on the task.
void CollectRow(const std::string& dir, const SlurmSubmission& sub, size_t task, const SlurmTaskRecord* slurm,
                StudyPointResult* r) {
  const nlohmann::json status = nlohmann::json::parse(ReadText(dir + "/slurm_status.json"), nullptr, false);
  const bool own = status.is_object() && status.value("job_id", "") == sub.job_id &&
                   status.value("array_task_id", -1) == int(task);
  const std::string state = slurm ? slurm->state : "UNKNOWN";
  const std::string slurm_exit = slurm ? slurm->exit_code : "";
  if (own && status["runtime_s"].is_number()) r->runtime_s = status["runtime_s"].get<double>();
  r->exit_code = own ? status.value("exit_code", -1) : slurm ? SlurmExitCode(slurm_exit) : -1;
  if (r->state == PointState::kResumed && own && r->exit_code == 0) {
    r->state = PointState::kRan;
    r->message.clear();
  } else {
    r->state = PointState::kFailed;
    r->metrics.assign(StudyMetrics().size(), std::numeric_limits<double>::quiet_NaN());
    r->message = "slurm job " + sub.job_id + "_" + std::to_string(task) + ": state " + state + ", exit code " +
                 (slurm_exit.empty() ? "unknown" : slurm_exit) +
                 (own ? "" : "; the task left no record of its own (killed before it finished?)");
    std::error_code ec;
    fs::remove(dir + "/metrics.json", ec);  // a failed point must not look finished
  }
  nlohmann::json j = {{"id", r->point.id}, {"state", PointStateName(r->state)}, {"exit_code", r->exit_code},
                      {"message", r->message}, {"backend", "slurm"}, {"slurm_job_id", sub.job_id},
                      {"slurm_array_task_id", task}, {"slurm_state", state}, {"slurm_exit_code", slurm_exit}};
  if (std::isfinite(r->runtime_s)) j["runtime_s"] = r->runtime_s;
  if (Status s = WriteFileAtomically(dir + "/point_status.json", j.dump(2) + "\n"); !s && r->message.empty())
    r->message = s.message;
}

}  // namespace

Status ReadSlurmSubmission(const std::string& out_dir, SlurmSubmission* submission, bool* exists) {
  const std::string path = JobJsonPath(out_dir);
  *exists = fs::exists(path);
  if (!*exists) return Status::Ok();
  const nlohmann::json j = nlohmann::json::parse(ReadText(path), nullptr, false);
  if (!j.is_object() || !j.contains("job_id") || !j["job_id"].is_string() || !j.contains("points") ||
      !j["points"].is_array())
    return Status::Error(path + ": not a submission record (job_id, dir, points, collected)");
  SlurmSubmission s;
  s.job_id = j["job_id"].get<std::string>();
  s.dir = j.value("dir", "");
  for (const nlohmann::json& id : j["points"])
    if (id.is_string()) s.point_ids.push_back(id.get<std::string>());
  s.collected = j.value("collected", false);
  *submission = std::move(s);
  return Status::Ok();
}

Status SlurmJobActive(const std::string& job_id, bool* active) {
  TaskMap tasks;
  bool known = false;
  if (Status s = QueryJob(job_id, &tasks, &known); !s) return s;
  *active = false;
  for (const auto& [k, r] : tasks) *active |= !IsFinalSlurmState(r.state);
  return Status::Ok();
}

Status SubmitSlurmStudy(const StudyConfig& config, const SlurmRunOptions& options, SlurmSubmission* submission,
                        bool* submitted) {
  *submitted = false;
  if (FindOnPath("sbatch").empty())
    return Status::Error("sbatch not found on PATH: --backend slurm needs Slurm's client commands (Debian: "
                         "slurm-client) and a cluster (SLURM_CONF); or use --backend local");
  SlurmSubmission previous;
  bool exists = false;
  if (Status s = ReadSlurmSubmission(options.out_dir, &previous, &exists); !s) return s;
  bool active = false;
  if (exists && !previous.collected)
    if (Status s = SlurmJobActive(previous.job_id, &active); !s) return s;
  if (active)
    return Status::Error("slurm job " + previous.job_id + " (submitted into " + options.out_dir + ") is still " +
                         "pending or running: wait for it with --collect, or cancel it with scancel " +
                         previous.job_id);
  if (exists && !previous.collected) {  // finished but never collected: record its tasks' states first
    StudyResult unused;
    bool stopped = false;
    if (Status s = CollectSlurmStudy(config, options, &unused, &stopped); !s) return s;
  }
  std::vector<StudyPoint> points;
  if (Status s = ExpandStudy(config, &points); !s) return s;
  StudyResult rows;
  std::vector<size_t> pending;
  if (Status s = PrepareStudyPoints(points, options.out_dir, &rows, &pending); !s) return s;
  if (pending.empty()) return Status::Ok();
  const std::string abs_out = fs::absolute(options.out_dir).lexically_normal().string();
  SlurmSubmission sub;
  sub.dir = NextSubmitDir(abs_out + "/slurm");
  for (size_t i : pending) {
    sub.point_ids.push_back(rows.points[i].point.id);
    std::error_code ec;
    fs::remove(abs_out + "/points/" + sub.point_ids.back() + "/slurm_status.json", ec);
  }
  if (Status s = WriteSubmitFiles(abs_out, config.slam_config_path, OwnExecutable(options.executable), &sub); !s)
    return s;
  CapturedOutput o;
  const std::vector<std::string> args = SbatchArgs(options.slurm, "rotolidar-study-" + config.name,
                                                   sub.point_ids.size(), sub.dir + "/logs", sub.dir + "/task.sh");
  if (Status s = RunCaptured(args, &o); !s) return s;
  sub.job_id = ParseSbatchJobId(o.out);
  if (o.exit_code != 0 || sub.job_id.empty())
    return Status::Error("sbatch refused the study (exit " + std::to_string(o.exit_code) + "): " + o.err + o.out);
  if (Status s = WriteSubmission(options.out_dir, sub); !s) return s;
  if (options.progress)
    options.progress("[study] submitted slurm job " + sub.job_id + ": " + std::to_string(sub.point_ids.size()) +
                     " array tasks (" + std::to_string(rows.points.size() - pending.size()) + " points finished " +
                     "earlier); task script " + sub.dir + "/task.sh");
  *submission = sub;
  *submitted = true;
  return Status::Ok();
}

Status CollectSlurmStudy(const StudyConfig& config, const SlurmRunOptions& options, StudyResult* result,
                         bool* stopped) {
  SlurmSubmission sub;
  bool exists = false;
  if (Status s = ReadSlurmSubmission(options.out_dir, &sub, &exists); !s) return s;
  if (!exists)
    return Status::Error(JobJsonPath(options.out_dir) + ": no Slurm submission to collect (run with --backend "
                         "slurm first)");
  TaskMap seen;
  if (!sub.collected)
    if (Status s = WaitForJob(sub, options, &seen, stopped); !s || *stopped) return s;
  std::vector<StudyPoint> points;
  if (Status s = ExpandStudy(config, &points); !s) return s;
  StudyResult res;
  std::vector<size_t> pending;
  if (Status s = PrepareStudyPoints(points, options.out_dir, &res, &pending); !s) return s;
  std::map<std::string, size_t> task_of;
  for (size_t k = 0; k < sub.point_ids.size(); ++k) task_of[sub.point_ids[k]] = k;
  for (StudyPointResult& r : res.points) {
    const auto it = task_of.find(r.point.id);
    if (it == task_of.end() || sub.collected) {
      if (r.state != PointState::kResumed) r.message = "not run: submit it with --backend slurm (or run locally)";
      continue;
    }
    const auto slurm = seen.find(it->second);
    CollectRow(options.out_dir + "/points/" + r.point.id, sub, it->second,
               slurm == seen.end() ? nullptr : &slurm->second, &r);
    if (r.state == PointState::kFailed && options.progress)
      options.progress("[study] point " + r.point.id + " FAILED (" + r.message + "); log: " + options.out_dir +
                       "/points/" + r.point.id + "/log.txt");
  }
  FinishStudyResult(&res);
  sub.collected = true;
  if (Status s = WriteSubmission(options.out_dir, sub); !s) return s;
  *result = std::move(res);
  return Status::Ok();
}

}  // namespace rotolidar::bench
