#pragma once
// A one-node Slurm cluster on loopback for tests: a private munged, slurmctld and slurmd (Debian packages
// munge, slurmctld, slurmd, slurm-client; .ci/setup.sh installs them), every file under one folder, bound to
// 127.0.0.1 on free ports, selected by SLURM_CONF (set in this process's environment, so the commands and the
// code under test that this process starts talk to this cluster only).
//
// The configuration avoids what a container without systemd lacks (Slurm's slurm.conf(5) documents each key):
// proctrack/linuxproc and task/none instead of the cgroup plugins, no accounting database (accounting_storage/
// none; jobcomp/filetxt writes one line per finished job or array task to jobcomp_path()),
// SlurmctldHost=localhost(127.0.0.1) and NodeName=localhost NodeAddr=127.0.0.1 so nothing depends on the
// machine's name or DNS, CommunicationParameters=NoInAddrAny,NoCtldInAddrAny to bind loopback only, and
// SchedulerParameters=bf_interval=1 for ~1 s scheduling waves.
#include <sys/types.h>

#include <string>

namespace rotolidar::testing_slurm {

class LoopbackSlurm {
 public:
  LoopbackSlurm() = default;
  LoopbackSlurm(const LoopbackSlurm&) = delete;
  LoopbackSlurm& operator=(const LoopbackSlurm&) = delete;
  ~LoopbackSlurm() { Stop(); }

  /// Writes the key, slurm.conf and state folders under dir (created; must not be shared with another
  /// cluster), sets SLURM_CONF, starts munged, slurmctld and slurmd, and waits up to timeout_s for the node to
  /// be idle. Returns "" on success, else one line saying why Slurm cannot run here (a missing program, a daemon
  /// that exited, a node that never became idle: with the tail of the daemons' logs). Stop() is safe after a
  /// failed Start.
  std::string Start(const std::string& dir, double timeout_s = 30.0);

  /// Cancels every job, waits (up to 30 s) until squeue lists none — running steps outlive the daemons and then
  /// ignore SIGTERM — then stops slurmd, slurmctld and munged (SIGTERM, SIGKILL after 10 s) and reaps them.
  void Stop();

  const std::string& dir() const { return dir_; }
  std::string conf_path() const { return dir_ + "/slurm.conf"; }
  std::string jobcomp_path() const { return dir_ + "/jobcomp.txt"; }

 private:
  std::string WriteConfig(int ctld_port, int slurmd_port);
  std::string WaitIdle(double timeout_s);
  std::string LogTails() const;

  std::string dir_;
  pid_t munged_ = -1, slurmctld_ = -1, slurmd_ = -1;
};

}  // namespace rotolidar::testing_slurm
