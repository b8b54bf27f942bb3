#include "tests/bench/study/slurm_cluster.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "bench/study/process_capture.hpp"

extern char** environ;

namespace rotolidar::testing_slurm {
namespace {

namespace fs = std::filesystem;
using bench::CapturedOutput;
using bench::FindOnPath;
using bench::RunCaptured;
using Clock = std::chrono::steady_clock;

/// A daemon program: on PATH, else in the sbin folders (not on every user's PATH).
std::string FindProgram(const std::string& name) {
  std::string path = FindOnPath(name);
  for (const char* dir : {"/usr/sbin/", "/sbin/", "/usr/local/sbin/"})
    if (path.empty()) path = FindOnPath(dir + name);
  return path;
}

/// A TCP port on 127.0.0.1 that is free now (bound to port 0, read back, closed); -1 on failure.
int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof(a);
  int port = -1;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
    port = ntohs(a.sin_port);
  ::close(fd);
  return port;
}

/// Starts argv in a new session (setsid: a terminal's Ctrl-C reaches the test, not the daemons), stdin from
/// /dev/null, stdout + stderr to log; -1 when it cannot start.
pid_t SpawnDaemon(const std::vector<std::string>& args, const std::string& log) {
  std::vector<char*> argv = bench::SpawnArgv(args);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSID);
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, argv[0], &actions, &attr, argv.data(), environ);
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

bool Exited(pid_t pid) {
  int status = 0;
  return pid > 0 && ::waitpid(pid, &status, WNOHANG) == pid;
}

/// SIGTERM, up to 10 s to exit, then SIGKILL; reaps it. *pid = -1 afterwards.
void StopDaemon(pid_t* pid) {
  if (*pid <= 0) return;
  ::kill(*pid, SIGTERM);
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  int status = 0;
  while (::waitpid(*pid, &status, WNOHANG) == 0) {
    if (Clock::now() > deadline) {
      ::kill(*pid, SIGKILL);
      ::waitpid(*pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  *pid = -1;
}

std::string Tail(const std::string& path, size_t bytes = 600) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string s = ss.str();
  return s.size() > bytes ? "..." + s.substr(s.size() - bytes) : s;
}

std::string UserName() {
  const passwd* pw = ::getpwuid(::geteuid());
  return pw ? pw->pw_name : std::to_string(::geteuid());
}

}  // namespace

std::string LoopbackSlurm::WriteConfig(int ctld_port, int slurmd_port) {
  std::ofstream key(dir_ + "/munge/munge.key", std::ios::binary);
  std::ifstream random("/dev/urandom", std::ios::binary);
  std::vector<char> bytes(1024);
  random.read(bytes.data(), bytes.size());
  key.write(bytes.data(), bytes.size());
  key.close();
  if (!random || !key || ::chmod((dir_ + "/munge/munge.key").c_str(), 0600) != 0) return "cannot write the munge key";
  const unsigned cpus = std::max(1u, std::thread::hardware_concurrency());
  const std::string user = UserName();
  std::ofstream conf(conf_path());
  conf << "ClusterName=rotolidartest\nSlurmctldHost=localhost(127.0.0.1)\nSlurmctldPort=" << ctld_port
       << "\nSlurmdPort=" << slurmd_port << "\nSlurmUser=" << user << "\nSlurmdUser=" << user
       << "\nAuthType=auth/munge\nCredType=cred/munge\nAuthInfo=socket=" << dir_ << "/munge/sock\n"
       << "CommunicationParameters=NoInAddrAny,NoCtldInAddrAny\nStateSaveLocation=" << dir_ << "/state\n"
       << "SlurmdSpoolDir=" << dir_ << "/spool\nSlurmctldPidFile=" << dir_ << "/slurmctld.pid\nSlurmdPidFile=" << dir_
       << "/slurmd.pid\nSlurmctldLogFile=" << dir_ << "/slurmctld.log\nSlurmdLogFile=" << dir_ << "/slurmd.log\n"
       << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\nSelectType=select/cons_tres\n"
       << "SelectTypeParameters=CR_Core\nJobAcctGatherType=jobacct_gather/none\n"
       << "AccountingStorageType=accounting_storage/none\nJobCompType=jobcomp/filetxt\nJobCompLoc=" << jobcomp_path()
       << "\nSchedulerParameters=bf_interval=1\nMpiDefault=none\nReturnToService=2\nKillWait=2\n"
       << "NodeName=localhost NodeAddr=127.0.0.1 CPUs=" << cpus << " RealMemory=1000 State=UNKNOWN\n"
       << "PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP\n";
  return conf ? "" : "cannot write " + conf_path();
}

std::string LoopbackSlurm::LogTails() const {
  std::string s;
  for (const char* log : {"munged.out", "slurmctld.out", "slurmd.out", "slurmctld.log", "slurmd.log"})
    if (fs::exists(dir_ + "/" + log)) s += std::string(" | ") + log + ": " + Tail(dir_ + "/" + log);
  return s;
}

std::string LoopbackSlurm::WaitIdle(double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  std::string state;
  while (Clock::now() < deadline) {
    for (auto [pid, name] : {std::pair{&munged_, "munged"}, {&slurmctld_, "slurmctld"}, {&slurmd_, "slurmd"}})
      if (Exited(*pid)) return *pid = -1, std::string(name) + " exited at start" + LogTails();
    CapturedOutput o;
    if (RunCaptured({"sinfo", "-h", "-n", "localhost", "-o", "%T"}, &o) && o.exit_code == 0) {
      state = o.out.substr(0, o.out.find('\n'));
      if (state == "idle") return "";
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return "the node did not become idle within " + std::to_string(timeout_s) + " s (last state '" + state + "')" +
         LogTails();
}

std::string LoopbackSlurm::Start(const std::string& dir, double timeout_s) {
  dir_ = fs::absolute(dir).lexically_normal().string();
  const std::string munged = FindProgram("munged"), ctld = FindProgram("slurmctld"), slurmd = FindProgram("slurmd");
  for (auto [path, name] : {std::pair{munged, "munged (package munge)"}, {ctld, "slurmctld (package slurmctld)"},
                            {slurmd, "slurmd (package slurmd)"}, {FindOnPath("sbatch"), "sbatch (slurm-client)"},
                            {FindOnPath("sinfo"), "sinfo (slurm-client)"}})
    if (path.empty()) return std::string(name) + " not found (bash .ci/setup.sh deps installs it)";
  std::error_code ec;
  for (const char* sub : {"/munge", "/state", "/spool"}) fs::create_directories(dir_ + sub, ec);
  if (ec) return dir_ + ": cannot create: " + ec.message();
  ::chmod(dir_.c_str(), 0755), ::chmod((dir_ + "/munge").c_str(), 0755);  // munged refuses group/world-writable
  const int ctld_port = FreePort(), slurmd_port = FreePort();
  if (ctld_port <= 0 || slurmd_port <= 0 || ctld_port == slurmd_port) return "no free TCP ports on 127.0.0.1";
  if (std::string why = WriteConfig(ctld_port, slurmd_port); !why.empty()) return why;
  ::setenv("SLURM_CONF", conf_path().c_str(), 1);
  const std::string m = dir_ + "/munge/";
  munged_ = SpawnDaemon({munged, "-F", "--socket=" + m + "sock", "--key-file=" + m + "munge.key",
                         "--pid-file=" + m + "munged.pid", "--log-file=" + m + "munged.log",
                         "--seed-file=" + m + "munged.seed"},
                        dir_ + "/munged.out");
  for (int i = 0; i < 100 && !fs::exists(m + "sock") && !Exited(munged_); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (!fs::exists(m + "sock")) return "munged did not create its socket" + LogTails();
  slurmctld_ = SpawnDaemon({ctld, "-D"}, dir_ + "/slurmctld.out");
  slurmd_ = SpawnDaemon({slurmd, "-D", "-N", "localhost"}, dir_ + "/slurmd.out");
  if (munged_ < 0 || slurmctld_ < 0 || slurmd_ < 0) return "cannot start the daemons";
  return WaitIdle(timeout_s);
}

void LoopbackSlurm::Stop() {
  if (slurmctld_ > 0) {
    CapturedOutput o;
    if (!RunCaptured({"scancel", "--user=" + UserName()}, &o)) o.exit_code = -1;  // then only the wait below
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    while (Clock::now() < deadline && RunCaptured({"squeue", "-h"}, &o) && o.exit_code == 0 && !o.out.empty())
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  StopDaemon(&slurmd_);
  StopDaemon(&slurmctld_);
  StopDaemon(&munged_);
}

}  // namespace rotolidar::testing_slurm
