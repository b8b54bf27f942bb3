#pragma once
// Progress lines for long runs, on stderr (stdout stays for results).
#include <chrono>
#include <functional>
#include <string>

namespace rotolidar::bench {

/// Returns a callback that prints "[label] 42% (elapsed 3.1 s)" when the fraction moves by >= 10 % or 5 s pass.
std::function<void(double)> MakeProgressPrinter(const std::string& label);

}  // namespace rotolidar::bench
