// libFuzzer's entry point for one target, chosen at compile time by ROTOLIDAR_FUZZ_NAME (tests/fuzz/CMakeLists.txt).
#include "tests/fuzz/fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static const rotolidar::fuzz::TargetFn target = rotolidar::fuzz::Registry().at(ROTOLIDAR_FUZZ_NAME);
  return target(data, size);
}
