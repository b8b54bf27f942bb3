#pragma once
// The VLP-16 twin's beam footprint and echo formation (docs/lidar_model.md): pure functions the caster applies
// to every laser firing, kept apart so that tests can drive them directly.
//
// Beam: a Gaussian spot whose 1/e^2 intensity contour grows with the full divergence angles (3.0 mrad along the
// scan x 1.5 mrad across it for the VLP-16). It is sampled by sub-rays on concentric rings of an ellipse in the
// plane across the central ray: ring j of n at radius j/n of the 1/e^2 contour, 6j sub-rays each, plus the
// central ray. Each sub-ray carries the beam power of the annulus it stands for (radii (j +- 1/2)/n), weighted
// by the Gaussian profile exp(-2 r^2); weights sum to 1.
//
// Echoes: every surface a sub-ray meets returns power p = weight * albedo * cos(incidence) * exp(-k r) * T^2
// (T = product of the transmittances of transmissive surfaces in front of it, crossed twice; a transmissive
// surface's own albedo is the fraction it reflects diffusely, its transmittance the fraction it passes on).
// The receiver cannot separate returns closer than the echo separation (Velodyne: dual return records both only
// when the objects are >= 1 m apart): sorted by range, returns within that distance of an echo's first return
// merge into it at their power-weighted mean range (a "mixed edge point" when they come from different surfaces)
// with their summed power. An echo is detected when 100 * power >= the intensity threshold.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "core/wire/vlp16.hpp"

namespace rotolidar::sim {

/// One sub-ray of the beam pattern: offsets in units of the half divergence (x along the scan, y across it;
/// x^2 + y^2 <= 1) and its share of the beam power.
struct BeamSample {
  double x = 0.0;
  double y = 0.0;
  double weight = 1.0;
};

/// 1 + 6 + 12 + ... + 6n samples for n rings (n = 0: the central ray alone, weight 1).
inline std::vector<BeamSample> BeamPattern(int rings) {
  std::vector<BeamSample> samples;
  const double n = std::max(rings, 1);
  samples.push_back({0.0, 0.0, M_PI / 4.0 / (n * n)});  // disk of radius 1/(2n)
  for (int j = 1; j <= rings; ++j) {
    const double r = j / n;
    const int count = 6 * j;
    const double w = std::exp(-2.0 * r * r) * M_PI / (3.0 * n * n);  // annulus area 2 pi j / n^2, per sample
    for (int k = 0; k < count; ++k) {
      const double phi = 2.0 * M_PI * (k + 0.5 * (j % 2)) / count;  // odd rings staggered by half a step
      samples.push_back({r * std::cos(phi), r * std::sin(phi), w});
    }
  }
  double total = 0.0;
  for (const BeamSample& s : samples) total += s.weight;
  for (BeamSample& s : samples) s.weight /= total;
  return samples;
}

/// What one surface sends back along one sub-ray (power on the reflectivity scale: 1 = a white Lambertian
/// target filling the beam, head-on).
struct SurfaceReturn {
  double range_m = 0.0;       ///< true range along the sub-ray
  double power = 0.0;
  bool retroreflective = false;
  double cos_incidence = 1.0;  ///< of the sub-ray on the surface
};

/// A detectable pulse at the receiver.
struct Echo {
  double range_m = 0.0;       ///< power-weighted mean range of the merged returns (noise-free)
  double power = 0.0;         ///< summed power
  bool retroreflective = false;  ///< most of its power comes from retroreflective surfaces
  double cos_incidence = 1.0;    ///< power-weighted mean over the merged returns
};

/// Sorts `returns` by range and merges them into echoes (see the file comment). Returns of zero power are
/// ignored. Appends to *echoes in range order.
inline void FormEchoes(SurfaceReturn* returns, std::size_t n, double separation_m, std::vector<Echo>* echoes) {
  std::sort(returns, returns + n, [](const SurfaceReturn& a, const SurfaceReturn& b) {
    return a.range_m < b.range_m;
  });
  double first_m = 0.0, weighted_m = 0.0, retro_power = 0.0, weighted_cos = 0.0;
  bool open = false;
  auto close = [&] {
    if (!open) return;
    Echo& e = echoes->back();
    e.range_m = weighted_m / e.power;
    e.cos_incidence = weighted_cos / e.power;
    e.retroreflective = retro_power > 0.5 * e.power;
    open = false;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const SurfaceReturn& r = returns[i];
    if (!(r.power > 0.0)) continue;
    if (!open || r.range_m - first_m >= separation_m) {
      close();
      echoes->push_back(Echo{});
      first_m = r.range_m;
      weighted_m = retro_power = weighted_cos = 0.0;
      open = true;
    }
    Echo& e = echoes->back();
    e.power += r.power;
    weighted_m += r.power * r.range_m;
    weighted_cos += r.power * r.cos_incidence;
    if (r.retroreflective) retro_power += r.power;
  }
  close();
}

/// Which echoes a firing reports: indices into the echo list, -1 = none.
struct EchoChoice {
  int primary = -1;    ///< single-return modes: the strongest / last echo; dual mode: the last echo (even block)
  int secondary = -1;  ///< dual mode only (odd block): the strongest, or the second strongest when the strongest
                       ///< is also the last; equals primary when only one echo was detected
};

/// A retroreflector's light goes back into the aperture instead of a hemisphere (orders of magnitude more than
/// a diffuse surface): it outranks every diffuse echo; otherwise the larger power wins, the nearer on a tie.
inline bool Stronger(const Echo& a, const Echo& b) {
  if (a.retroreflective != b.retroreflective) return a.retroreflective;
  if (a.power != b.power) return a.power > b.power;
  return a.range_m < b.range_m;
}

/// Chooses the reported echoes among those with 100 * power >= min_intensity and range in [min_m, max_m].
inline EchoChoice ChooseEchoes(const std::vector<Echo>& echoes, Vlp16ReturnMode mode, double min_intensity,
                               double min_m, double max_m) {
  int strongest = -1, second = -1, last = -1;
  for (int i = 0; i < static_cast<int>(echoes.size()); ++i) {
    const Echo& e = echoes[static_cast<std::size_t>(i)];
    if (100.0 * e.power < min_intensity || e.range_m < min_m || e.range_m > max_m) continue;
    last = i;  // echoes come in range order
    if (strongest < 0 || Stronger(e, echoes[static_cast<std::size_t>(strongest)])) {
      second = strongest;
      strongest = i;
    } else if (second < 0 || Stronger(e, echoes[static_cast<std::size_t>(second)])) {
      second = i;
    }
  }
  EchoChoice choice;
  if (last < 0) return choice;
  switch (mode) {
    case Vlp16ReturnMode::kStrongest: choice.primary = strongest; break;
    case Vlp16ReturnMode::kLast: choice.primary = last; break;
    case Vlp16ReturnMode::kDual:
      choice.primary = last;
      choice.secondary = strongest != last ? strongest : (second >= 0 ? second : last);
      break;
  }
  return choice;
}

}  // namespace rotolidar::sim
