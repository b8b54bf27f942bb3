#include "bench/run/progress.hpp"

#include <cstdio>
#include <memory>

namespace rotolidar::bench {

std::function<void(double)> MakeProgressPrinter(const std::string& label) {
  struct State {
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now(), last = start;
    double last_fraction = -1.0;
  };
  auto state = std::make_shared<State>();
  return [label, state](double fraction) {
    const auto now = std::chrono::steady_clock::now();
    const double since_last = std::chrono::duration<double>(now - state->last).count();
    if (fraction < 1.0 && fraction - state->last_fraction < 0.1 && since_last < 5.0) return;
    state->last = now;
    state->last_fraction = fraction;
    const double elapsed = std::chrono::duration<double>(now - state->start).count();
    std::fprintf(stderr, "[%s] %3.0f%% (elapsed %.1f s)\n", label.c_str(), 100.0 * fraction, elapsed);
  };
}

}  // namespace rotolidar::bench
