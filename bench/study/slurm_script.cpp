#include "bench/study/slurm_script.hpp"

#include <cctype>
#include <regex>
#include <set>
#include <sstream>

namespace rotolidar::bench {
namespace {

/// The value of "Key=" in a `scontrol -o` record (words separated by spaces); "" when absent.
std::string Field(const std::string& line, const std::string& key) {
  std::istringstream words(line);
  std::string w;
  while (words >> w)
    if (w.compare(0, key.size() + 1, key + "=") == 0) return w.substr(key.size() + 1);
  return "";
}

/// "3", "4-9%2", "1,4-6" -> the indices (a throttle suffix "%N" is dropped). Empty on malformed input.
std::vector<size_t> ParseTaskIds(std::string ids) {
  if (const size_t pct = ids.find('%'); pct != std::string::npos) ids.resize(pct);
  std::vector<size_t> out;
  std::istringstream parts(ids);
  std::string part;
  while (std::getline(parts, part, ',')) {
    size_t a = 0, b = 0;
    char dash = 0;
    std::istringstream in(part);
    if (!(in >> a)) return {};
    b = a;
    if (in >> dash && (dash != '-' || !(in >> b) || b < a)) return {};
    for (size_t k = a; k <= b; ++k) out.push_back(k);
  }
  return out;
}

}  // namespace

bool StudySlurmConfig::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = "slurm." + m;
    return false;
  };
  static const std::regex time_re(R"(^(\d+-\d+(:\d+){0,2}|\d+(:\d+){0,2}|UNLIMITED|INFINITE)$)");
  static const std::regex mem_re(R"(^\d+[KMGT]?$)");
  static const std::regex partition_re(R"(^[A-Za-z0-9_.,-]*$)");
  if (!std::regex_match(time_per_point, time_re))
    return fail("time_per_point: '" + time_per_point + "' is not a Slurm time (MM, MM:SS, HH:MM:SS, D-HH, " +
                "D-HH:MM, D-HH:MM:SS)");
  if (!std::regex_match(mem_per_point, mem_re))
    return fail("mem_per_point: '" + mem_per_point + "' is not a Slurm memory size (a number, optional K/M/G/T)");
  if (!std::regex_match(partition, partition_re))
    return fail("partition: '" + partition + "': letters, digits, '_', '.', '-' or ','");
  if (cpus_per_point < 1) return fail("cpus_per_point: must be >= 1");
  if (max_parallel < 0) return fail("max_parallel: must be >= 0 (0 = no throttle)");
  if (!(poll_interval_s >= 0.05 && poll_interval_s <= 3600.0)) return fail("poll_interval_s: in [0.05, 3600] s");
  for (const std::string& a : sbatch_args)
    if (a.size() < 2 || a[0] != '-') return fail("sbatch_args: '" + a + "' is not an option (starts with '-')");
  return true;
}

std::string ShellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string SlurmTaskScript(const SlurmTaskScriptSpec& spec) {
  std::ostringstream sh;
  sh << "#!/bin/sh\n"
        "# A rotolidar study array task (written by `rotolidar study --backend slurm`): array task k runs the\n"
        "# point on line k + 1 of the points file with the local backend's command, then records its exit status.\n"
        "set -u\n"
     << "points=" << ShellQuote(spec.points_file) << "\n"
     << "id=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" \"$points\")\n"
        "if [ -z \"$id\" ]; then echo \"no point for array task $SLURM_ARRAY_TASK_ID in $points\" >&2; exit 2; fi\n"
     << "dir=" << ShellQuote(spec.out_dir + "/points") << "/\"$id\"\n"
     << "start=$(date +%s.%N)\n"
     << ShellQuote(spec.executable) << " demo --out \"$dir\" --config \"$dir/sim_config.yaml\"";
  if (!spec.slam_config_path.empty()) sh << " --slam-config " << ShellQuote(spec.slam_config_path);
  sh << " < /dev/null > \"$dir/log.txt\" 2>&1\n"
        "rc=$?\n"
        "end=$(date +%s.%N)\n"
        "runtime=$(awk -v a=\"$start\" -v b=\"$end\" 'BEGIN { printf \"%.3f\", b - a }')\n"
        "printf '{\"job_id\": \"%s\", \"array_task_id\": %d, \"node\": \"%s\", "
        "\"exit_code\": %d, \"runtime_s\": %s}\\n' "
        "\"${SLURM_ARRAY_JOB_ID:-}\" \"$SLURM_ARRAY_TASK_ID\" \"${SLURMD_NODENAME:-}\" \"$rc\" \"$runtime\" "
        "> \"$dir/slurm_status.json.tmp\" && mv -f \"$dir/slurm_status.json.tmp\" \"$dir/slurm_status.json\"\n"
        "exit $rc\n";
  return sh.str();
}

std::vector<std::string> SbatchArgs(const StudySlurmConfig& c, const std::string& job_name, size_t tasks,
                                    const std::string& logs_dir, const std::string& script_path) {
  std::string array = "--array=0-" + std::to_string(tasks == 0 ? 0 : tasks - 1);
  if (c.max_parallel > 0) array += "%" + std::to_string(c.max_parallel);
  std::vector<std::string> args = {"sbatch", "--parsable", "--job-name=" + job_name, array,
                                   "--output=" + logs_dir + "/%A_%a.out", "--time=" + c.time_per_point,
                                   "--mem=" + c.mem_per_point, "--cpus-per-task=" + std::to_string(c.cpus_per_point)};
  if (!c.partition.empty()) args.push_back("--partition=" + c.partition);
  args.insert(args.end(), c.sbatch_args.begin(), c.sbatch_args.end());
  args.push_back(script_path);
  return args;
}

std::string ParseSbatchJobId(const std::string& out) {
  std::string id;
  for (char c : out) {
    if (!std::isdigit(static_cast<unsigned char>(c))) break;
    id += c;
  }
  return id;
}

std::map<size_t, SlurmTaskRecord> ParseScontrolJobs(const std::string& text) {
  std::map<size_t, SlurmTaskRecord> tasks;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const std::string ids = Field(line, "ArrayTaskId");
    if (ids.empty()) continue;
    const SlurmTaskRecord r{Field(line, "JobState"), Field(line, "ExitCode"), Field(line, "Reason")};
    for (size_t k : ParseTaskIds(ids)) tasks[k] = r;
  }
  return tasks;
}

bool IsFinalSlurmState(const std::string& state) {
  static const std::set<std::string> final_states = {"COMPLETED", "FAILED",    "TIMEOUT",   "CANCELLED",
                                                     "OUT_OF_MEMORY", "NODE_FAIL", "PREEMPTED", "BOOT_FAIL",
                                                     "DEADLINE"};
  return final_states.count(state) > 0;
}

int SlurmExitCode(const std::string& exit_code) {
  int status = 0, signal = 0;
  char colon = 0;
  std::istringstream in(exit_code);
  if (!(in >> status >> colon >> signal) || colon != ':') return -1;
  return signal > 0 ? 128 + signal : status;
}

}  // namespace rotolidar::bench
