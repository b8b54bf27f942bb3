// Simulated VLP-16 head: schedule, ray casting in batches, range/intensity model (see the header).
#include "sim/lidar/vlp16_caster.hpp"

#include <algorithm>
#include <cmath>

namespace rotolidar::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr int kLasers = 16;
constexpr int kSequencesPerBatch = 32;  // 512 rays per Embree stream call
constexpr double kMaxEncodableRangeM = 65535 * kVlp16DistanceUnitM;

bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

}  // namespace

bool Vlp16CasterConfig::Validate(std::string* error) const {
  if (!std::isfinite(t0_s)) return Fail(error, "lidar.t0_s must be finite");
  if (!std::isfinite(azimuth0_deg)) return Fail(error, "lidar.azimuth0_deg must be finite");
  if (!(rpm > 0.0 && rpm <= 1200.0)) return Fail(error, "lidar.rpm must be in (0, 1200]");
  if (!(rpm_jitter_frac >= 0.0 && rpm_jitter_frac < 0.5)) {
    return Fail(error, "lidar.rpm_jitter_frac must be in [0, 0.5)");
  }
  if (!(rpm_jitter_tau_s > 0.0)) return Fail(error, "lidar.rpm_jitter_tau_s must be > 0");
  if (!(range_noise_sigma_m >= 0.0 && range_noise_sigma_m < 1.0)) {
    return Fail(error, "lidar.range_noise_sigma_m must be in [0, 1)");
  }
  if (!(min_range_m >= 0.0)) return Fail(error, "lidar.min_range_m must be >= 0");
  if (!(max_range_m > min_range_m && max_range_m <= kMaxEncodableRangeM)) {
    return Fail(error, "lidar.max_range_m must be in (min_range_m, 131.07]");
  }
  if (!(grazing_cutoff_deg > 0.0 && grazing_cutoff_deg <= 90.0)) {
    return Fail(error, "lidar.grazing_cutoff_deg must be in (0, 90]");
  }
  if (!(min_intensity_for_return >= 0.0 && min_intensity_for_return <= 100.0)) {
    return Fail(error, "lidar.min_intensity_for_return must be in [0, 100]");
  }
  if (!(intensity_attenuation_per_m >= 0.0 && intensity_attenuation_per_m < 1.0)) {
    return Fail(error, "lidar.intensity_attenuation_per_m must be in [0, 1)");
  }
  return true;
}

Vlp16Caster::Vlp16Caster(const EmbreeScene& scene, const LidarIntrinsics& intrinsics,
                         const Vlp16CasterConfig& config, uint64_t run_seed)
    : scene_(scene),
      intrinsics_(intrinsics),
      config_(config),
      range_rng_(run_seed, "lidar.range"),
      rpm_rng_(run_seed, "lidar.rpm") {
  std::string error;
  ROTOLIDAR_CHECK(config_.Validate(&error), error);
  head_azimuth_deg_ = std::fmod(config_.azimuth0_deg, 360.0);
  if (head_azimuth_deg_ < 0.0) head_azimuth_deg_ += 360.0;
  if (config_.rpm_jitter_frac > 0.0) spin_error_ = rpm_rng_.Normal();  // start in the stationary distribution
  spin_rate_degps_ = config_.rpm * 6.0 * (1.0 + config_.rpm_jitter_frac * spin_error_);
  // At exactly 90 deg the cutoff only drops rays parallel to the surface.
  cos_grazing_cutoff_ = std::cos(config_.grazing_cutoff_deg * kDegToRad);
}

Seconds Vlp16Caster::FiringTime(int64_t sequence_index, int laser_id) const {
  return config_.t0_s + static_cast<double>(sequence_index) * kVlp16SequencePeriodS +
         static_cast<double>(laser_id) * kVlp16FiringPeriodS;
}

void Vlp16Caster::AdvanceSpinRate() {
  head_azimuth_deg_ = std::fmod(head_azimuth_deg_ + spin_rate_degps_ * kVlp16SequencePeriodS, 360.0);
  if (config_.rpm_jitter_frac <= 0.0) return;
  const double a = std::exp(-kVlp16SequencePeriodS / config_.rpm_jitter_tau_s);
  spin_error_ = a * spin_error_ + std::sqrt(1.0 - a * a) * rpm_rng_.Normal();
  spin_rate_degps_ = config_.rpm * 6.0 * (1.0 + config_.rpm_jitter_frac * spin_error_);
}

void Vlp16Caster::PlanSequence(const std::function<Pose3(Seconds)>& T_world_lidar_at, Vlp16FiringSequence* seq,
                               Firing* firings) {
  seq->t_s = FiringTime(next_sequence_, 0);
  seq->azimuth_centideg = static_cast<uint16_t>(std::llround(head_azimuth_deg_ * 100.0) % 36000);
  for (int i = 0; i < kLasers; ++i) {
    Firing& f = firings[i];
    f.t_s = FiringTime(next_sequence_, i);
    const double azimuth_rad = (head_azimuth_deg_ + spin_rate_degps_ * i * kVlp16FiringPeriodS) * kDegToRad;
    const Pose3 T_world_lidar = T_world_lidar_at(f.t_s);
    f.origin_world = T_world_lidar * Vlp16RayOrigin(intrinsics_.vertical_offset_m[i]);
    const Eigen::Vector3d dir_lidar = Vlp16RayDirection(intrinsics_.elevation_deg[i] * kDegToRad, azimuth_rad);
    f.dir_world = (T_world_lidar.linear() * dir_lidar).normalized();
  }
  ++next_sequence_;
  AdvanceSpinRate();
}

void Vlp16Caster::Measure(const Firing& firing, const RayHit& hit, int laser_id, uint16_t* distance_2mm,
                          uint8_t* reflectivity, LidarTruthPoint* truth) {
  const double noise_m = config_.range_noise_sigma_m * range_rng_.Normal();  // drawn for every firing
  *distance_2mm = 0;
  *reflectivity = 0;
  truth->t_s = firing.t_s;
  truth->laser_id = static_cast<uint8_t>(laser_id);
  truth->hit = hit.hit;
  truth->returned = false;
  if (!hit.hit) return;
  truth->true_range_m = hit.distance_m;
  truth->p_world = firing.origin_world + hit.distance_m * firing.dir_world;

  const double cos_incidence = -hit.normal_world.dot(firing.dir_world);
  if (cos_incidence < cos_grazing_cutoff_ || cos_incidence <= 0.0) return;
  const Material& material = scene_.material(hit.material_id);
  const double s = material.albedo * cos_incidence * std::exp(-config_.intensity_attenuation_per_m * hit.distance_m);
  if (100.0 * s < config_.min_intensity_for_return) return;
  const double measured_m = hit.distance_m + noise_m;
  if (measured_m < config_.min_range_m || measured_m > config_.max_range_m) return;
  const long long units = std::llround(measured_m / kVlp16DistanceUnitM);
  if (units <= 0 || units > 65535) return;

  *distance_2mm = static_cast<uint16_t>(units);
  const long long byte = material.retroreflective ? 101 + std::llround(154.0 * s) : std::llround(100.0 * s);
  *reflectivity = static_cast<uint8_t>(std::clamp<long long>(byte, 0, 255));
  truth->returned = true;
}

void Vlp16Caster::Fire(int num_sequences, const std::function<Pose3(Seconds)>& T_world_lidar_at,
                       std::vector<Vlp16FiringSequence>* out, std::vector<LidarTruthPoint>* truth_out) {
  ROTOLIDAR_CHECK(out != nullptr, "Fire needs an output");
  ROTOLIDAR_CHECK(num_sequences >= 0, "num_sequences = " << num_sequences);
  std::vector<Firing> firings(kSequencesPerBatch * kLasers);
  std::vector<RayQuery> queries(firings.size());
  std::vector<RayHit> hits(firings.size());
  out->reserve(out->size() + static_cast<std::size_t>(num_sequences));
  if (truth_out) truth_out->reserve(truth_out->size() + static_cast<std::size_t>(num_sequences) * kLasers);

  for (int done = 0; done < num_sequences; done += kSequencesPerBatch) {
    const int n_seq = std::min(kSequencesPerBatch, num_sequences - done);
    const std::size_t first = out->size();
    out->resize(first + static_cast<std::size_t>(n_seq));
    for (int s = 0; s < n_seq; ++s) {
      PlanSequence(T_world_lidar_at, &(*out)[first + s], &firings[static_cast<std::size_t>(s) * kLasers]);
    }
    const std::size_t n_rays = static_cast<std::size_t>(n_seq) * kLasers;
    for (std::size_t r = 0; r < n_rays; ++r) {
      queries[r] = RayQuery{firings[r].origin_world, firings[r].dir_world, config_.max_range_m};
    }
    scene_.IntersectBatch(queries.data(), n_rays, hits.data());
    for (int s = 0; s < n_seq; ++s) {
      Vlp16FiringSequence& seq = (*out)[first + s];
      for (int i = 0; i < kLasers; ++i) {
        const std::size_t r = static_cast<std::size_t>(s) * kLasers + i;
        LidarTruthPoint truth;
        Measure(firings[r], hits[r], i, &seq.distance_2mm[i], &seq.reflectivity[i], &truth);
        if (truth_out) truth_out->push_back(truth);
      }
      seq.distance2_2mm = seq.distance_2mm;
      seq.reflectivity2 = seq.reflectivity;
    }
  }
}

}  // namespace rotolidar::sim
