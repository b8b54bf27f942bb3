#pragma once
// One fuzz target = one parser fed arbitrary bytes. Each target file defines and registers its targets with
// ROTOLIDAR_FUZZ_TARGET. In the normal build every target is linked into fuzz_regression_test, which replays the
// committed corpus (tests/fuzz/corpus/<name>/) through it; with ROTOLIDAR_FUZZ=ON (clang) each target is also a
// libFuzzer executable, fuzz_<name> (fuzz_libfuzzer_main.cpp picks the target by name; docs/testing.md). A target returns 0 and must never crash, hang or leak:
// every input is either parsed or refused with a Status.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include <unistd.h>

namespace rotolidar::fuzz {

using TargetFn = int (*)(const uint8_t* data, std::size_t size);

/// Every target linked into this binary, by name (the regression test iterates it).
inline std::map<std::string, TargetFn>& Registry() {
  static std::map<std::string, TargetFn> targets;
  return targets;
}

struct Register {
  Register(const char* name, TargetFn fn) { Registry()[name] = fn; }
};

/// Writes the input into a file of this process (loaders take paths); returns its path. `name` keeps the
/// extension or the file name a loader dispatches on (e.g. "x.ply", "calib.yaml").
inline std::string WriteInput(const uint8_t* data, std::size_t size, const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("rotolidar_fuzz_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), size);
  return path;
}

}  // namespace rotolidar::fuzz

/// Defines and registers a target: ROTOLIDAR_FUZZ_TARGET(name) { body using data, size }.
#define ROTOLIDAR_FUZZ_TARGET(name)                                                    \
  static int FuzzBody_##name(const uint8_t* data, std::size_t size);                  \
  static const ::rotolidar::fuzz::Register kRegister_##name(#name, &FuzzBody_##name); \
  static int FuzzBody_##name(const uint8_t* data, std::size_t size)
