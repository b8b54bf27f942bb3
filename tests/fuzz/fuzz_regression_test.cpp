// Every fuzz target over its committed corpus (tests/fuzz/corpus/<target>/), as a plain test: each input must be
// parsed or refused without a crash. Inputs that once crashed a target are kept in its corpus (a fix and its
// proof). Fuzzing itself is not part of the test run: docs/testing.md says how to fuzz each target for N minutes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "tests/fuzz/fuzz_target.hpp"

namespace rotolidar::fuzz {
namespace {

TEST(FuzzRegression, EveryTargetTakesItsCorpus) {
  const std::filesystem::path corpus = ROTOLIDAR_FUZZ_CORPUS_DIR;
  ASSERT_FALSE(Registry().empty());
  for (const auto& [name, target] : Registry()) {
    const std::filesystem::path dir = corpus / name;
    ASSERT_TRUE(std::filesystem::is_directory(dir)) << "no corpus for target " << name << " in " << dir;
    // The empty input first, as libFuzzer does (it once crashed PCL's PCD reader).
    const uint8_t none = 0;  // a valid pointer, as libFuzzer passes
    EXPECT_EQ(target(&none, 0), 0) << name << ": the empty input";
    std::size_t inputs = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      std::ifstream in(entry.path(), std::ios::binary);
      const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      SCOPED_TRACE(entry.path().string());
      EXPECT_EQ(target(bytes.data(), bytes.size()), 0);
      ++inputs;
    }
    EXPECT_GT(inputs, 0u) << name;
    std::printf("%-16s %zu inputs\n", name.c_str(), inputs);
  }
}

}  // namespace
}  // namespace rotolidar::fuzz
