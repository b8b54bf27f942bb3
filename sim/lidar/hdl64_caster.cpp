// Simulated HDL-64E S2 (see the header): elevation table, ray casting in chunks of columns, range and
// reflectance model.
#include "sim/lidar/hdl64_caster.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;

}  // namespace

double Hdl64ElevationDeg(int laser) {
  ROTOLIDAR_CHECK(laser >= 0 && laser < kHdl64Lasers, "laser " << laser);
  // Upper block: +2.0 deg down in 1/3 deg steps to -8.33; lower block: -8.83 down in 1/2 deg steps to -24.33.
  return laser < 32 ? 2.0 - laser / 3.0 : -8.83 - 0.5 * (laser - 32);
}

bool Hdl64CasterConfig::Validate(std::string* error) const {
  if (!(revolution_hz >= 5.0 && revolution_hz <= 20.0)) {
    return FailValidation(error, "hdl64.revolution_hz must be in [5, 20] (the HDL-64E's spin range)");
  }
  if (!(firings_per_revolution >= 36 && firings_per_revolution <= 20000)) {
    return FailValidation(error, "hdl64.firings_per_revolution must be in [36, 20000]");
  }
  if (!(range_noise_sigma_m >= 0.0 && range_noise_sigma_m < 1.0)) {
    return FailValidation(error, "hdl64.range_noise_sigma_m must be in [0, 1)");
  }
  if (!(min_range_m >= 0.0)) return FailValidation(error, "hdl64.min_range_m must be >= 0");
  if (!(max_range_m > min_range_m && max_range_m <= 1000.0)) {
    return FailValidation(error, "hdl64.max_range_m must be in (min_range_m, 1000]");
  }
  if (!(grazing_cutoff_deg > 0.0 && grazing_cutoff_deg <= 90.0)) {
    return FailValidation(error, "hdl64.grazing_cutoff_deg must be in (0, 90]");
  }
  if (!(min_reflectance >= 0.0 && min_reflectance < 1.0))
    return FailValidation(error, "hdl64.min_reflectance must be in [0, 1)");
  if (!(intensity_attenuation_per_m >= 0.0 && intensity_attenuation_per_m < 1.0)) {
    return FailValidation(error, "hdl64.intensity_attenuation_per_m must be in [0, 1)");
  }
  if (!(std::abs(elevation_error_deg) <= 5.0))
    return FailValidation(error, "hdl64.elevation_error_deg must be in [-5, 5]");
  if (!(columns_per_chunk >= 1 && columns_per_chunk <= 4096)) {
    return FailValidation(error, "hdl64.columns_per_chunk must be in 1..4096");
  }
  return true;
}

Eigen::Vector3d Hdl64Caster::RayDirection(int laser, double azimuth_rad) {
  const double e = Hdl64ElevationDeg(laser) * kDegToRad;
  return Eigen::Vector3d(std::cos(e) * std::cos(azimuth_rad), std::cos(e) * std::sin(azimuth_rad), std::sin(e));
}

Hdl64Caster::Hdl64Caster(EmbreeScene* scene, const Hdl64CasterConfig& config, uint64_t run_seed)
    : scene_(scene), config_(config), range_rng_(run_seed, "hdl64.range") {
  std::string error;
  ROTOLIDAR_CHECK(scene_ != nullptr, "Hdl64Caster needs a scene");
  ROTOLIDAR_CHECK(config_.Validate(&error), error);
  cos_grazing_cutoff_ = std::cos(config_.grazing_cutoff_deg * kDegToRad);
  for (int i = 0; i < kHdl64Lasers; ++i) {
    dir0_[size_t(i)] = RayDirection(i, 0.0);
    const double e = (Hdl64ElevationDeg(i) + config_.elevation_error_deg) * kDegToRad;
    reported0_[size_t(i)] = Eigen::Vector3d(std::cos(e), 0.0, std::sin(e));
  }
  const size_t n = size_t(config_.columns_per_chunk) * kHdl64Lasers;
  queries_.resize(n);
  hits_.resize(n);
  dir_lidar_.resize(n);
}

void Hdl64Caster::Revolution(Seconds t0_s, const std::function<Pose3(Seconds)>& T_world_lidar_at,
                             std::vector<Hdl64Point>* out) {
  ROTOLIDAR_CHECK(out != nullptr, "Revolution needs an output");
  for (auto& line : lines_) {
    line.clear();
    line.reserve(size_t(config_.firings_per_revolution));
  }
  for (int c = 0; c < config_.firings_per_revolution; c += config_.columns_per_chunk) {
    CastChunk(t0_s, c, std::min(config_.columns_per_chunk, config_.firings_per_revolution - c), T_world_lidar_at);
  }
  out->clear();
  size_t total = 0;
  for (const auto& line : lines_) total += line.size();
  out->reserve(total);
  for (const auto& line : lines_) out->insert(out->end(), line.begin(), line.end());
}

// Plans `columns` columns from first_column (queries laser-major: neighbouring rays one azimuth step apart, which
// Embree's coherent stream traverses faster), casts them, and appends the measured points to lines_.
void Hdl64Caster::CastChunk(Seconds t0_s, int first_column, int columns,
                            const std::function<Pose3(Seconds)>& pose_at) {
  const double dt_s = period_s() / config_.firings_per_revolution;
  const double step_rad = 2.0 * kPi / config_.firings_per_revolution;
  if (scene_->num_dynamic_objects() > 0) scene_->SetTime(t0_s + first_column * dt_s);
  std::vector<Pose3> poses(size_t(columns), Pose3::Identity());
  for (int c = 0; c < columns; ++c) poses[size_t(c)] = pose_at(t0_s + (first_column + c) * dt_s);
  for (int i = 0; i < kHdl64Lasers; ++i) {
    for (int c = 0; c < columns; ++c) {
      const size_t q = size_t(i) * size_t(columns) + size_t(c);
      const double a = (first_column + c) * step_rad;
      const Eigen::Vector3d& d0 = dir0_[size_t(i)];
      dir_lidar_[q] = Eigen::Vector3d(d0.x() * std::cos(a), d0.x() * std::sin(a), d0.z());
      const Pose3& T = poses[size_t(c)];
      queries_[q] = RayQuery{T.translation(), T.linear() * dir_lidar_[q], config_.max_range_m};
    }
  }
  const size_t n = size_t(columns) * kHdl64Lasers;
  scene_->IntersectBatch(queries_.data(), n, hits_.data());
  for (size_t q = 0; q < n; ++q) {
    const double noise_m = config_.range_noise_sigma_m * range_rng_.Normal();  // drawn for every ray
    const RayHit& hit = hits_[q];
    if (!hit.hit) continue;
    const double cos_incidence = -hit.normal_world.dot(queries_[q].dir_world.normalized());
    if (cos_incidence <= 0.0 || cos_incidence < cos_grazing_cutoff_) continue;
    const double range_m = hit.distance_m + noise_m;
    if (range_m < config_.min_range_m || range_m > config_.max_range_m) continue;
    const double reflectance = std::clamp(scene_->material(hit.material_id).albedo * cos_incidence *
                                              std::exp(-config_.intensity_attenuation_per_m * hit.distance_m),
                                          0.0, 1.0);
    if (reflectance < config_.min_reflectance) continue;
    const int laser = int(q / size_t(columns));
    const int column = first_column + int(q % size_t(columns));
    Eigen::Vector3d p = range_m * dir_lidar_[q];
    if (config_.elevation_error_deg != 0.0) {  // the same azimuth, the reported elevation
      const Eigen::Vector3d& r0 = reported0_[size_t(laser)];
      const Eigen::Vector2d u = dir_lidar_[q].head<2>().normalized();
      p = range_m * Eigen::Vector3d(r0.x() * u.x(), r0.x() * u.y(), r0.z());
    }
    lines_[size_t(laser)].push_back(Hdl64Point{float(p.x()), float(p.y()), float(p.z()), float(reflectance),
                                               float(column * dt_s), uint8_t(laser)});
  }
}

}  // namespace rotolidar::sim
