// The default study point runner: `rotolidar demo` on the point's config, as a child process of this executable.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "bench/study/process_capture.hpp"
#include "bench/study/study_runner.hpp"

extern char** environ;

namespace rotolidar::bench {
namespace {

/// Spawns argv[0] with stdin from /dev/null and stdout + stderr appended to log_path; waits for it.
PointRunOutcome SpawnAndWait(const std::vector<std::string>& args, const std::string& log_path) {
  std::vector<char*> argv = SpawnArgv(args);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) return {-1, "cannot start " + args[0] + ": " + std::strerror(rc)};
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return {-1, std::string("waitpid: ") + std::strerror(errno)};
  }
  if (WIFEXITED(status)) {
    const int code = WEXITSTATUS(status);
    return {code, code == 0 ? "" : "exit status " + std::to_string(code)};
  }
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    return {128 + sig, "killed by signal " + std::to_string(sig) + " (" + strsignal(sig) + ")"};
  }
  return {-1, "child ended in an unknown way"};
}

}  // namespace

PointRunner MakeDemoProcessRunner(const std::string& executable, const std::string& slam_config_path) {
  std::string exe = executable;
  if (exe.empty()) {
    std::error_code ec;
    exe = std::filesystem::read_symlink("/proc/self/exe", ec).string();
    if (ec) exe = "/proc/self/exe";
  }
  return [exe, slam_config_path](const StudyPoint&, const std::string& point_dir) {
    std::vector<std::string> args = {exe, "demo", "--out", point_dir, "--config", point_dir + "/sim_config.yaml"};
    if (!slam_config_path.empty()) args.insert(args.end(), {"--slam-config", slam_config_path});
    return SpawnAndWait(args, point_dir + "/log.txt");
  };
}

}  // namespace rotolidar::bench
