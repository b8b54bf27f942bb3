// The VLP-16 twin's range physics beyond the schedule and the echoes (contract in vlp16_caster.hpp, models in
// docs/lidar_model.md sections 4 and 5): validation of its fields, the noise model, range walk and blooming.
#include <algorithm>
#include <cmath>

#include "core/util/validation.hpp"
#include "sim/lidar/vlp16_caster.hpp"

namespace rotolidar::sim {

bool Vlp16CasterConfig::ValidateRangePhysics(std::string* error) const {
  if (!(range_noise_per_m >= 0.0 && range_noise_per_m < 0.1)) {
    return FailValidation(error, "lidar.range_noise_per_m must be in [0, 0.1)");
  }
  if (!(range_noise_incidence_exponent >= 0.0 && range_noise_incidence_exponent <= 4.0)) {
    return FailValidation(error, "lidar.range_noise_incidence_exponent must be in [0, 4]");
  }
  if (!(range_noise_min_cos > 0.0 && range_noise_min_cos <= 1.0)) {
    return FailValidation(error, "lidar.range_noise_min_cos must be in (0, 1]");
  }
  if (!(range_noise_weak_power >= 0.0 && range_noise_weak_power <= 1.0)) {
    return FailValidation(error, "lidar.range_noise_weak_power must be in [0, 1]");
  }
  if (!(range_noise_weak_max_gain >= 1.0 && range_noise_weak_max_gain <= 100.0)) {
    return FailValidation(error, "lidar.range_noise_weak_max_gain must be in [1, 100]");
  }
  for (std::size_t i = 0; i < range_bias_curve.size(); ++i) {
    const auto& [byte, bias_m] = range_bias_curve[i];
    if (!(byte >= 0.0 && byte <= 255.0 && std::abs(bias_m) < 1.0) ||
        (i > 0 && !(byte > range_bias_curve[i - 1][0]))) {
      return FailValidation(error,
                            "lidar.range_bias_curve: [byte, bias_m] points need increasing bytes in [0, 255] and "
                            "|bias_m| < 1");
    }
  }
  if (!(bloom_halo_mrad >= 0.0 && bloom_halo_mrad <= 100.0)) {
    return FailValidation(error, "lidar.bloom_halo_mrad must be in [0, 100]");
  }
  if (!(bloom_power_fraction > 0.0 && bloom_power_fraction <= 1.0)) {
    return FailValidation(error, "lidar.bloom_power_fraction must be in (0, 1]");
  }
  return true;
}

double Vlp16Caster::RangeSigma(const Echo& e) const {
  double sigma = config_.range_noise_sigma_m;
  if (config_.range_noise_per_m > 0.0) sigma = std::hypot(sigma, config_.range_noise_per_m * e.range_m);
  if (config_.range_noise_incidence_exponent > 0.0) {
    sigma /= std::pow(std::max(e.cos_incidence, config_.range_noise_min_cos), config_.range_noise_incidence_exponent);
  }
  if (!e.retroreflective && e.power < config_.range_noise_weak_power) {
    sigma *= std::min(config_.range_noise_weak_max_gain, std::sqrt(config_.range_noise_weak_power / e.power));
  }
  return sigma;
}

double Vlp16Caster::RangeBias(int byte) const {
  const auto& curve = config_.range_bias_curve;
  if (curve.empty()) return 0.0;
  if (byte <= curve.front()[0]) return curve.front()[1];
  for (std::size_t i = 1; i < curve.size(); ++i) {
    if (byte <= curve[i][0]) {
      const double f = (byte - curve[i - 1][0]) / (curve[i][0] - curve[i - 1][0]);
      return curve[i - 1][1] + f * (curve[i][1] - curve[i - 1][1]);
    }
  }
  return curve.back()[1];
}

// Blooming: firings whose central ray passes within the halo of a retroreflector's bounding sphere cast 16 halo
// rays (two rings at the halo's edge and half way); the strongest of those that see a retroreflective surface
// first becomes one more return of the firing, at bloom_power_fraction of that surface's power. A firing that
// already has a retroreflective return gets none (its own echo is the retroreflector's).
void Vlp16Caster::AddBloom(std::size_t n_firings) {
  const double halo_rad = 1e-3 * config_.bloom_halo_mrad;
  const double tan_halo = std::tan(halo_rad);
  halo_firings_.clear();
  halo_queries_.clear();
  for (std::size_t f = 0; f < n_firings; ++f) {
    const SurfaceReturn* returns = &returns_[f * return_capacity_];
    bool has_retro = false;
    for (int i = 0; i < return_counts_[f]; ++i) has_retro = has_retro || returns[i].retroreflective;
    if (has_retro) continue;
    const Firing& firing = firings_[f];
    bool near = false;
    for (const RetroSphere& sphere : retro_spheres_) {
      const Eigen::Vector3d to_c = sphere.center - firing.origin_world;
      const double dist = to_c.norm();
      if (dist <= sphere.radius_m) { near = true; break; }
      const double angle = std::acos(std::clamp(to_c.dot(firing.dir_world) / dist, -1.0, 1.0));
      if (angle <= std::asin(sphere.radius_m / dist) + halo_rad) { near = true; break; }
    }
    if (!near) continue;
    halo_firings_.push_back(f);
    const Eigen::Vector3d u = firing.dir_world.unitOrthogonal();
    const Eigen::Vector3d v = firing.dir_world.cross(u);
    for (const BeamSample& s : halo_pattern_) {
      const Eigen::Vector3d d = firing.dir_world + tan_halo * (s.x * u + s.y * v);
      halo_queries_.push_back(RayQuery{firing.origin_world, d.normalized(), config_.max_range_m});
    }
  }
  if (halo_queries_.empty()) return;
  halo_hits_.resize(halo_queries_.size());
  scene_.IntersectBatch(halo_queries_.data(), halo_queries_.size(), halo_hits_.data());
  const std::size_t per = halo_pattern_.size();
  for (std::size_t i = 0; i < halo_firings_.size(); ++i) {
    SurfaceReturn best;
    for (std::size_t k = 0; k < per; ++k) {
      const RayHit& hit = halo_hits_[i * per + k];
      if (!hit.hit || !scene_.material(hit.material_id).retroreflective) continue;
      const double cos_incidence = -hit.normal_world.dot(halo_queries_[i * per + k].dir_world);
      if (cos_incidence < cos_grazing_cutoff_ || cos_incidence <= 0.0) continue;
      const double power = config_.bloom_power_fraction * scene_.material(hit.material_id).albedo * cos_incidence *
                           std::exp(-config_.intensity_attenuation_per_m * hit.distance_m);
      if (power > best.power) best = SurfaceReturn{hit.distance_m, power, true, cos_incidence};
    }
    const std::size_t f = halo_firings_[i];
    if (best.power > 0.0 && static_cast<std::size_t>(return_counts_[f]) < return_capacity_) {
      returns_[f * return_capacity_ + static_cast<std::size_t>(return_counts_[f]++)] = best;
    }
  }
}

}  // namespace rotolidar::sim
