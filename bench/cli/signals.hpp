#pragma once
// Clean stops for long commands: while a StopOnSignals lives, SIGINT (Ctrl-C) and SIGTERM set a flag that the
// command's loop polls (it then finishes what it has, writes its outputs and says that they are partial) instead
// of killing the process. A second signal of either kind kills it at once (the default action is restored after
// the first). One instance at a time; the process-wide handler is the only global state.
#include <atomic>
#include <csignal>

namespace rotolidar::bench {

class StopOnSignals {
 public:
  StopOnSignals() {
    Flag() = false;
    Signal() = 0;
    std::signal(SIGINT, &StopOnSignals::Handle);
    std::signal(SIGTERM, &StopOnSignals::Handle);
  }
  ~StopOnSignals() {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

  const std::atomic<bool>& flag() const { return Flag(); }
  int signal() const { return Signal(); }  ///< the signal received (0: none)
  const char* name() const { return Signal() == SIGINT ? "SIGINT" : Signal() == SIGTERM ? "SIGTERM" : "none"; }

 private:
  static void Handle(int sig) {
    Signal() = sig;
    Flag() = true;
    std::signal(sig, SIG_DFL);  // a second Ctrl-C ends the process
  }
  static std::atomic<bool>& Flag() {
    static std::atomic<bool> flag{false};
    return flag;
  }
  static std::atomic<int>& Signal() {
    static std::atomic<int> signal{0};
    return signal;
  }
};

}  // namespace rotolidar::bench
