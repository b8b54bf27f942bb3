#pragma once
// The VLP-16 twin's part of the realism presets (sim/realism.hpp): which range physics each preset switches on
// and with what magnitudes. Numbers and their sources: docs/lidar_model.md, section 5 ("Presets").
#include "sim/lidar/vlp16_caster.hpp"
#include "sim/realism.hpp"

namespace rotolidar::sim {

/// Sets c's range-physics fields for preset r and leaves every other field (schedule, return mode, materials,
/// ranges) alone:
///  - kIdeal: the caster's defaults (constant 3 cm Gaussian noise, no bias, no blooming, no mirrors, central ray);
///  - kTypical: the fitted noise floor (2 cm) with a mild incidence growth (1/cos, at most 2x), range walk,
///    blooming, mirrors (central ray: the casting stays ~30x real time);
///  - kHarsh: the full fit (ApplyFittedVlp16Noise) with 1.5x its noise, as through a worn or dirty window (weak
///    echoes noisier still), a larger range walk, a wider bloom halo, and a 7-ray beam for mixed edge points.
void ApplyLidarRealism(Realism r, Vlp16CasterConfig* c);

/// Sets only the range-noise model to the one fitted to the real VLP-16 capture (docs/lidar_model.md): sigma =
/// 2 cm / max(cos(incidence), 0.1)^2.5, no range term, no weak-echo term.
void ApplyFittedVlp16Noise(Vlp16CasterConfig* c);

}  // namespace rotolidar::sim
