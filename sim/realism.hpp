#pragma once
// The twin's realism presets: one switch that sets every modelled error source of a run (rig calibration errors,
// vibration, clocks, the VLP-16's range physics, the IMU's noise) to the magnitudes of an ideal, a typical or a
// harsh real rig. Each source can still be set alone after the preset (a config's explicit keys win). What each
// preset sets, and why those magnitudes: docs/noise_models.md.
#include <string>
#include <utility>
#include <vector>

#include "core/util/status.hpp"

namespace rotolidar::sim {

enum class Realism {
  kIdeal,    ///< no calibration error, no vibration, synced clocks, Gaussian range noise only
  kTypical,  ///< a carefully built and calibrated rig: errors at the magnitudes real rigs report
  kHarsh,    ///< a rushed build or a rough carrier: the upper end of those magnitudes
};

/// Words in YAML and on the command line: ideal, typical, harsh.
const std::vector<std::pair<const char*, Realism>>& EnumWords(Realism*);

/// Sets *r to the preset named `word`; otherwise an error listing the words (and *r untouched).
Status RealismFromWord(const std::string& word, Realism* r);

}  // namespace rotolidar::sim
