#pragma once
// The VLP-16 twin's part of the realism presets (sim/realism.hpp): which range physics each preset switches on
// and with what magnitudes. Numbers and their sources: docs/lidar_model.md, section 5 ("Presets").
#include "sim/lidar/vlp16_caster.hpp"
#include "sim/realism.hpp"

namespace rotolidar::sim {

/// Sets c's range-physics fields for preset r and leaves every other field (schedule, return mode, materials,
/// ranges) alone:
///  - kIdeal: the caster's defaults (constant 3 cm Gaussian noise, no bias, no blooming, no mirrors, central ray);
///  - kTypical: the noise model fitted to a real VLP-16 capture, range walk, blooming, mirrors (central ray: the
///    casting stays ~30x real time);
///  - kHarsh: a worn or dirty window: more noise (weak echoes noisier still), larger range walk, a wider bloom
///    halo, and a 7-ray beam for mixed edge points (~7x real time).
void ApplyLidarRealism(Realism r, Vlp16CasterConfig* c);

}  // namespace rotolidar::sim
