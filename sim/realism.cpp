#include "sim/realism.hpp"

namespace rotolidar::sim {

const std::vector<std::pair<const char*, Realism>>& EnumWords(Realism*) {
  static const std::vector<std::pair<const char*, Realism>> words = {
      {"ideal", Realism::kIdeal}, {"typical", Realism::kTypical}, {"harsh", Realism::kHarsh}};
  return words;
}

}  // namespace rotolidar::sim
