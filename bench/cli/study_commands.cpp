// `rotolidar study STUDY.yaml`: trade studies (bench/study/, docs/studies.md), on local cores or on Slurm.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <thread>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/cli/signals.hpp"
#include "bench/study/slurm_backend.hpp"
#include "bench/study/study_config.hpp"
#include "bench/study/study_report.hpp"
#include "bench/study/study_runner.hpp"

namespace rotolidar::bench {
namespace {

void AddStudyOptions(OptionParser& p) {
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const StudySlurmConfig d;
  p.AddPositional("STUDY", "study YAML (docs/studies.md)");
  p.Add("out", "", "-", "output folder (default runs/study_<STUDY file name>)");
  p.Add("backend", "local", "-", "local: child processes on this machine; slurm: one sbatch --array job");
  p.Add("jobs", std::to_string(hw), "-", "local: points run at once (default: this machine's hardware threads)");
  p.AddFlag("list", "print the points and their folders, run nothing");
  p.AddFlag("detach", "slurm: submit and return; gather later with --collect");
  p.AddFlag("collect", "wait for the submitted Slurm job of --out (if still running), then gather its results");
  p.Add("partition", d.partition, "-", "slurm: sbatch --partition (default: study file slurm.partition, else "
                                       "the cluster's default)");
  p.Add("time", d.time_per_point, "-", "slurm: time limit per point, Slurm's format (default: slurm.time_per_point)");
  p.Add("mem", d.mem_per_point, "-", "slurm: memory per point, e.g. 2G (default: slurm.mem_per_point)");
  p.Add("cpus-per-point", std::to_string(d.cpus_per_point), "-", "slurm: sbatch --cpus-per-task");
  p.Add("max-parallel", std::to_string(d.max_parallel), "-", "slurm: array throttle %N (0 = none)");
  p.Add("sbatch-args", "", "-", "slurm: extra sbatch options, space-separated (appended to slurm.sbatch_args)");
  p.Add("poll-interval", "10", "s", "slurm: how often to ask Slurm for the tasks' states");
}

/// The command line's Slurm options over the study file's; false (message on stderr) on a bad value.
bool ApplySlurmFlags(const OptionParser& p, StudySlurmConfig* c) {
  if (p.IsSet("partition")) c->partition = p.Get("partition");
  if (p.IsSet("time")) c->time_per_point = p.Get("time");
  if (p.IsSet("mem")) c->mem_per_point = p.Get("mem");
  long n = 0;
  double x = 0;
  if (p.IsSet("cpus-per-point")) {
    if (Status s = p.GetInt("cpus-per-point", &n); !s) return std::cerr << "error: " << s.message << "\n", false;
    c->cpus_per_point = int(n);
  }
  if (p.IsSet("max-parallel")) {
    if (Status s = p.GetInt("max-parallel", &n); !s) return std::cerr << "error: " << s.message << "\n", false;
    c->max_parallel = int(n);
  }
  if (p.IsSet("poll-interval")) {
    if (Status s = p.GetDouble("poll-interval", &x); !s) return std::cerr << "error: " << s.message << "\n", false;
    c->poll_interval_s = x;
  }
  std::istringstream extra(p.Get("sbatch-args"));
  for (std::string a; extra >> a;) c->sbatch_args.push_back(a);
  std::string why;
  if (!c->Validate(&why)) return std::cerr << "error: command line: " << why << "\n", false;
  return true;
}

void Say(const std::string& line) { std::printf("%s\n", line.c_str()), std::fflush(stdout); }

/// A Slurm job submitted into out and not collected, still running: the local backend must not race it.
bool SlurmJobBlocksLocal(const std::string& out) {
  SlurmSubmission sub;
  bool exists = false, active = false;
  if (!ReadSlurmSubmission(out, &sub, &exists) || !exists || sub.collected) return false;
  if (Status s = SlurmJobActive(sub.job_id, &active); !s) {
    std::fprintf(stderr, "[study] warning: %s has an uncollected Slurm job %s whose state is unknown (%s)\n",
                 out.c_str(), sub.job_id.c_str(), s.message.c_str());
    return false;
  }
  if (active)
    std::fprintf(stderr, "error: slurm job %s is still running into %s: --collect it or scancel %s first\n",
                 sub.job_id.c_str(), out.c_str(), sub.job_id.c_str());
  return active;
}

/// The Slurm backend: submit (unless --collect), then wait and gather (unless --detach). *gathered = false when
/// nothing is to be written (detached or stopped); the return value is then the exit code.
int RunOnSlurm(const OptionParser& p, const StudyConfig& config, SlurmRunOptions& o, StopOnSignals& stop,
               StudyResult* result, bool* gathered) {
  *gathered = false;
  o.progress = Say;
  o.stop = &stop.flag();
  if (!p.Flag("collect")) {
    SlurmSubmission sub;
    bool submitted = false;
    if (Status s = SubmitSlurmStudy(config, o, &sub, &submitted); !s) return Fail(s);
    if (!submitted) Say("[study] every point is finished: nothing to submit");
    if (submitted && p.Flag("detach")) {
      Say("[study] detached; gather the results with: rotolidar study " + p.Get("STUDY") + " --out " + o.out_dir +
          " --collect");
      return 0;
    }
  }
  bool stopped = false;
  if (Status s = CollectSlurmStudy(config, o, result, &stopped); !s) return Fail(s);
  if (stopped) {
    std::fprintf(stderr, "[study] stopped waiting by %s; the Slurm job keeps running: gather it with --collect\n",
                 stop.name());
    return 128 + stop.signal();
  }
  *gathered = true;
  return 0;
}

int WriteAndSummarize(const StudyConfig& config, const StudyResult& result, const std::string& out) {
  if (Status s = WriteStudyOutputs(config, result, out); !s) return Fail(s);
  std::printf("[study] %s: %zu points (%zu run, %zu finished earlier, %zu failed)\n  table: %s/study.csv\n"
              "  page : %s\n",
              config.name.c_str(), result.points.size(), result.ran, result.resumed, result.failed, out.c_str(),
              std::filesystem::absolute(out + "/study.html").c_str());
  return 0;
}

int ListPoints(const StudyConfig& config, const std::string& out) {
  std::vector<StudyPoint> points;
  if (Status s = ExpandStudy(config, &points); !s) return Fail(s);
  for (const StudyPoint& pt : points) std::printf("%4zu  %s/points/%s\n", pt.index, out.c_str(), pt.id.c_str());
  return 0;
}

}  // namespace

int CmdStudy(int argc, char** argv) {
  OptionParser p("study",
                 "Trade study: expand the sweep of STUDY.yaml (full factorial), run sim + SLAM + evaluation for each "
                 "point (`rotolidar demo`) as a child process on local cores or as one Slurm array job, and write "
                 "study.csv, plots/*.svg and study.html. Rerunning resumes on either backend: finished points "
                 "(metrics.json present) are skipped, failed ones run again.");
  AddStudyOptions(p);
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  StudyConfig config;
  if (Status s = LoadStudyConfig(p.Get("STUDY"), &config); !s) return Fail(s);
  std::string out = p.Get("out");
  if (out.empty()) out = "runs/study_" + std::filesystem::path(p.Get("STUDY")).stem().string();
  long jobs = 0;
  if (Status s = p.GetInt("jobs", &jobs); !s || jobs < 1)
    return std::cerr << "error: --jobs must be an integer >= 1\n", 2;
  const std::string backend = p.Get("backend");
  if (backend != "local" && backend != "slurm")
    return std::cerr << "error: --backend: unknown value '" << backend << "' (local or slurm)\n", 2;
  const bool slurm = backend == "slurm" || p.Flag("collect");
  if (p.Flag("detach") && !slurm) return std::cerr << "error: --detach needs --backend slurm\n", 2;
  if (!ApplySlurmFlags(p, &config.slurm)) return 2;
  if (p.Flag("list")) return ListPoints(config, out);
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  std::filesystem::copy_file(p.Get("STUDY"), out + "/study.yaml", std::filesystem::copy_options::overwrite_existing,
                             ec);
  StopOnSignals stop;  // Ctrl-C / SIGTERM: local: start no new point, write what is done; slurm: stop waiting
  StudyResult result;
  if (slurm) {
    SlurmRunOptions o;
    o.out_dir = out, o.slurm = config.slurm;
    bool gathered = false;
    if (int rc = RunOnSlurm(p, config, o, stop, &result, &gathered); !gathered) return rc;
  } else {
    if (SlurmJobBlocksLocal(out)) return 1;
    StudyRunOptions options;
    options.out_dir = out;
    options.jobs = int(jobs);
    options.progress = Say;
    options.stop = &stop.flag();
    if (Status s = RunStudy(config, options, MakeDemoProcessRunner("", config.slam_config_path), &result); !s)
      return Fail(s);
  }
  if (int rc = WriteAndSummarize(config, result, out); rc != 0) return rc;
  if (!slurm && stop.signal() != 0) {
    std::fprintf(stderr, "[study] stopped by %s: %zu points not run; the same command resumes the study\n",
                 stop.name(), result.not_run);
    return 128 + stop.signal();
  }
  return result.failed > 0 ? 1 : 0;
}

}  // namespace rotolidar::bench
