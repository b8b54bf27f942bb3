// Simulated VLP-16 head: schedule, ray casting in batches, beam/echo, range and intensity model (see the header).
#include "sim/lidar/vlp16_caster.hpp"

#include <algorithm>
#include <boost/random/normal_distribution.hpp>
#include <cmath>

#include "core/util/log.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr int kLasers = 16;
constexpr int kSequencesPerBatch = 32;  // 512 firings per Embree stream call
constexpr double kMaxEncodableRangeM = 65535 * kVlp16DistanceUnitM;
constexpr double kPassThroughM = 1e-4;  // a transmitted sub-ray restarts this far behind the surface it crossed

/// RandomStream as a UniformRandomBitGenerator for Boost's normal distribution: the Marsaglia-Tsang ziggurat
/// (header-only, a fixed algorithm, unlike std::normal_distribution), ~2x faster than RandomStream::Normal's
/// polar method; the range noise draws 289,344 normals per simulated second.
struct StreamBits {
  using result_type = uint64_t;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~result_type{0}; }
  result_type operator()() { return stream->NextU64(); }
  RandomStream* stream;
};

double StandardNormal(RandomStream* stream) {
  StreamBits bits{stream};
  return boost::random::normal_distribution<double>()(bits);
}

/// Room for `more` elements; grows at least 2x, so that callers appending packet by packet stay linear.
template <typename T>
void ReserveGeometric(std::vector<T>* v, std::size_t more) {
  if (v->capacity() - v->size() < more) v->reserve(std::max(2 * v->capacity(), v->size() + more));
}

}  // namespace

bool Vlp16CasterConfig::Validate(std::string* error) const {
  if (!std::isfinite(t0_s)) return FailValidation(error, "lidar.t0_s must be finite");
  if (!std::isfinite(azimuth0_deg)) return FailValidation(error, "lidar.azimuth0_deg must be finite");
  if (!(rpm >= 300.0 && rpm <= 1200.0))
    return FailValidation(error, "lidar.rpm must be in [300, 1200] (the VLP-16's range)");
  if (!(rpm_jitter_frac >= 0.0 && rpm_jitter_frac < 0.5)) {
    return FailValidation(error, "lidar.rpm_jitter_frac must be in [0, 0.5)");
  }
  if (!(rpm_jitter_tau_s > 0.0)) return FailValidation(error, "lidar.rpm_jitter_tau_s must be > 0");
  if (!(range_noise_sigma_m >= 0.0 && range_noise_sigma_m < 1.0)) {
    return FailValidation(error, "lidar.range_noise_sigma_m must be in [0, 1)");
  }
  if (!ValidateRangePhysics(error)) return false;
  if (!(min_range_m >= 0.0)) return FailValidation(error, "lidar.min_range_m must be >= 0");
  if (!(max_range_m > min_range_m && max_range_m <= kMaxEncodableRangeM)) {
    return FailValidation(error, "lidar.max_range_m must be in (min_range_m, 131.07]");
  }
  if (!(grazing_cutoff_deg > 0.0 && grazing_cutoff_deg <= 90.0)) {
    return FailValidation(error, "lidar.grazing_cutoff_deg must be in (0, 90]");
  }
  if (!(min_intensity_for_return >= 0.0 && min_intensity_for_return <= 100.0)) {
    return FailValidation(error, "lidar.min_intensity_for_return must be in [0, 100]");
  }
  if (!(intensity_attenuation_per_m >= 0.0 && intensity_attenuation_per_m < 1.0)) {
    return FailValidation(error, "lidar.intensity_attenuation_per_m must be in [0, 1)");
  }
  if (return_mode != Vlp16ReturnMode::kStrongest && return_mode != Vlp16ReturnMode::kLast &&
      return_mode != Vlp16ReturnMode::kDual) {
    return FailValidation(error, "lidar.return_mode must be strongest, last or dual");
  }
  if (!(beam_rings >= 0 && beam_rings <= 4)) return FailValidation(error, "lidar.beam_rings must be in 0..4");
  if (!(beam_divergence_horizontal_mrad >= 0.0 && beam_divergence_horizontal_mrad < 100.0)) {
    return FailValidation(error, "lidar.beam_divergence_horizontal_mrad must be in [0, 100)");
  }
  if (!(beam_divergence_vertical_mrad >= 0.0 && beam_divergence_vertical_mrad < 100.0)) {
    return FailValidation(error, "lidar.beam_divergence_vertical_mrad must be in [0, 100)");
  }
  if (!(echo_separation_m > 0.0 && echo_separation_m < 100.0)) {
    return FailValidation(error, "lidar.echo_separation_m must be in (0, 100)");
  }
  for (const auto& [name, t] : material_transmittance) {
    if (!(t >= 0.0 && t < 1.0))
      return FailValidation(error, "lidar.material_transmittance." + name + " must be in [0, 1)");
  }
  if (!(max_surfaces_per_ray >= 1 && max_surfaces_per_ray <= 8)) {
    return FailValidation(error, "lidar.max_surfaces_per_ray must be in 1..8");
  }
  return true;
}

Status CheckCasterMaterials(const Vlp16CasterConfig& config, const std::vector<Material>& materials) {
  for (const auto& entry : config.material_transmittance) {
    const std::string& name = entry.first;  // (C++17 lambdas cannot capture a structured binding)
    const double t = entry.second;
    const auto it = std::find_if(materials.begin(), materials.end(), [&](const Material& m) { return m.name == name; });
    if (it == materials.end()) {
      return Status::Error("lidar.material_transmittance: material '" + name + "' is not in the scene");
    }
    if (it->albedo + t > 1.0) {  // reflected + transmitted fractions of the incident power
      return Status::Error("lidar.material_transmittance: material '" + name + "': albedo " +
                           std::to_string(it->albedo) + " + transmittance " + std::to_string(t) + " exceeds 1");
    }
  }
  return Status::Ok();
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
  const Status materials = CheckCasterMaterials(config_, scene_.materials());
  ROTOLIDAR_CHECK(materials.ok, materials.message);
  head_azimuth_deg_ = std::fmod(config_.azimuth0_deg, 360.0);
  if (head_azimuth_deg_ < 0.0) head_azimuth_deg_ += 360.0;
  if (config_.rpm_jitter_frac > 0.0) spin_error_ = rpm_rng_.Normal();  // start in the stationary distribution
  spin_rate_degps_ = config_.rpm * 6.0 * (1.0 + config_.rpm_jitter_frac * spin_error_);
  // At exactly 90 deg the cutoff only drops rays parallel to the surface.
  cos_grazing_cutoff_ = std::cos(config_.grazing_cutoff_deg * kDegToRad);
  for (int i = 0; i < kLasers; ++i) {
    const Eigen::Vector3d d = Vlp16RayDirection(intrinsics_.elevation_deg[i] * kDegToRad, 0.0);
    cos_elevation_[i] = d.x();
    sin_elevation_[i] = d.z();
  }
  pattern_ = BeamPattern(config_.beam_rings);
  transmittance_.assign(scene_.materials().size(), 0.0);
  for (std::size_t m = 0; m < transmittance_.size(); ++m) {
    for (const auto& [name, t] : config_.material_transmittance) {
      if (scene_.materials()[m].name == name) transmittance_[m] = t;
    }
    any_transmissive_ = any_transmissive_ || transmittance_[m] > 0.0;
  }
  const std::size_t firings = kSequencesPerBatch * kLasers;
  firings_.resize(firings);
  queries_.resize(firings * pattern_.size());
  hits_.resize(queries_.size());
  return_capacity_ = pattern_.size() * static_cast<std::size_t>(config_.max_surfaces_per_ray) +
                     (config_.bloom_halo_mrad > 0.0 ? 1 : 0);
  returns_.resize(firings * return_capacity_);
  return_counts_.resize(firings);
  if (config_.bloom_halo_mrad > 0.0) {
    for (const Eigen::AlignedBox3d& box : scene_.retroreflective_bounds()) {
      retro_spheres_.push_back({box.center(), 0.5 * box.diagonal().norm()});
    }
    // Two staggered rings of 8 rays at the halo's edge and half way in (offsets in units of the halo radius).
    for (int k = 0; k < 16; ++k) {
      const double phi = 2.0 * kPi * (k / 2) / 8.0 + (k % 2) * kPi / 8.0;
      const double rho = k % 2 == 0 ? 1.0 : 0.5;
      halo_pattern_.push_back({rho * std::cos(phi), rho * std::sin(phi), 1.0});
    }
  }
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

// The interval the pose is interpolated over: from this sequence's start to the next one's (whose pose the next
// sequence reuses), or, for the last sequence of a Fire call, to its own last firing, so that the pose function is
// never asked about a time after the last firing it is covering (the sim's physics trace may end there).
void Vlp16Caster::SequencePoses(const PoseFn& T_world_lidar_at, bool last_in_call) {
  if (config_.pose_per_firing) return;
  pose_start_ = have_next_pose_ ? pose_next_ : T_world_lidar_at(FiringTime(next_sequence_, 0));
  if (last_in_call) {
    pose_next_ = T_world_lidar_at(FiringTime(next_sequence_, kLasers - 1));
    pose_span_s_ = (kLasers - 1) * kVlp16FiringPeriodS;
    have_next_pose_ = false;
  } else {
    pose_next_ = T_world_lidar_at(FiringTime(next_sequence_ + 1, 0));
    pose_span_s_ = kVlp16SequencePeriodS;
    have_next_pose_ = true;
  }
}

// Head azimuth of laser i: a0 + w * i * 2.304 us; its cosine/sine by rotating the previous laser's by one step.
void Vlp16Caster::PlanSequence(const PoseFn& T_world_lidar_at, Vlp16FiringSequence* seq, std::size_t s,
                               bool last_in_call) {
  Firing* firings = &firings_[s * kLasers];
  seq->t_s = FiringTime(next_sequence_, 0);
  seq->azimuth_centideg = static_cast<uint16_t>(std::llround(head_azimuth_deg_ * 100.0) % 36000);
  const double step_rad = spin_rate_degps_ * kVlp16FiringPeriodS * kDegToRad;
  const double cos_step = std::cos(step_rad), sin_step = std::sin(step_rad);
  double cos_a = std::cos(head_azimuth_deg_ * kDegToRad), sin_a = std::sin(head_azimuth_deg_ * kDegToRad);
  const double tan_h = std::tan(0.5e-3 * config_.beam_divergence_horizontal_mrad);
  const double tan_v = std::tan(0.5e-3 * config_.beam_divergence_vertical_mrad);
  const std::size_t k_rays = pattern_.size();
  SequencePoses(T_world_lidar_at, last_in_call);
  // Linear interpolation of the pose matrix over <= 55 us: the rotation is orthonormal to ~(w dt)^2 / 8 (< 1e-8
  // for w < 3 rad/s), far below the 2 mm range unit; directions are normalised below.
  const Eigen::Matrix3d dR = pose_next_.linear() - pose_start_.linear();
  const Eigen::Vector3d dt = pose_next_.translation() - pose_start_.translation();
  Pose3 T_world_lidar = pose_start_;
  for (int i = 0; i < kLasers; ++i) {
    Firing& f = firings[i];
    f.t_s = FiringTime(next_sequence_, i);
    if (config_.pose_per_firing) {
      T_world_lidar = T_world_lidar_at(f.t_s);
    } else {
      const double frac = i * kVlp16FiringPeriodS / pose_span_s_;
      T_world_lidar.linear() = pose_start_.linear() + frac * dR;
      T_world_lidar.translation() = pose_start_.translation() + frac * dt;
    }
    f.origin_world = T_world_lidar * Vlp16RayOrigin(intrinsics_.vertical_offset_m[i]);
    const double ce = cos_elevation_[i], se = sin_elevation_[i];
    const Eigen::Vector3d dir_lidar(ce * cos_a, -ce * sin_a, se);  // = Vlp16RayDirection(elev_i, a_i)
    f.dir_world = (T_world_lidar.linear() * dir_lidar).normalized();
    RayQuery* queries = &queries_[QueryIndex(s * kLasers + static_cast<std::size_t>(i), 0)];
    queries[0] = RayQuery{f.origin_world, f.dir_world, config_.max_range_m};
    if (k_rays > 1) {  // footprint axes: along the scan (d dir / d azimuth) and across it (d dir / d elevation)
      const Eigen::Vector3d u_h = T_world_lidar.linear() * Eigen::Vector3d(-sin_a, -cos_a, 0.0);
      const Eigen::Vector3d u_v = T_world_lidar.linear() * Eigen::Vector3d(-se * cos_a, se * sin_a, ce);
      for (std::size_t k = 1; k < k_rays; ++k) {
        const Eigen::Vector3d d = f.dir_world + pattern_[k].x * tan_h * u_h + pattern_[k].y * tan_v * u_v;
        queries[k] = RayQuery{f.origin_world, d.normalized(), config_.max_range_m};
      }
    }
    const double c = cos_a * cos_step - sin_a * sin_step;
    sin_a = sin_a * cos_step + cos_a * sin_step;
    cos_a = c;
  }
  ++next_sequence_;
  AdvanceSpinRate();
}

// Casts the batch's queries, then follows sub-rays through transmissive surfaces and, with specular_reflections,
// off mirrors (one more Embree call per surface depth, for the sub-rays that went on), collecting each firing's
// surface returns in returns_; then adds the bloom returns.
void Vlp16Caster::CastBatch(std::size_t n_firings) {
  const std::size_t k_rays = pattern_.size();
  std::fill(return_counts_.begin(), return_counts_.begin() + static_cast<std::ptrdiff_t>(n_firings), 0);
  std::size_t n = n_firings * k_rays;
  scene_.IntersectBatch(queries_.data(), n, hits_.data());
  const RayQuery* queries = queries_.data();
  const RayHit* hits = hits_.data();
  for (int depth = 0; n > 0; ++depth) {
    next_info_.clear();
    next_queries_.clear();
    for (std::size_t q = 0; q < n; ++q) {
      const RayHit& hit = hits[q];
      if (!hit.hit) continue;
      // Pass 0: query q is sub-ray q of the batch; later passes carry the sub-ray and its path so far.
      const Pass pass = depth == 0 ? Pass{q, 1.0, 0.0, false} : pass_info_[q];
      const std::size_t firing = FiringOfQuery(pass.ray);
      const RayQuery& query = queries[q];
      const double range_m = depth == 0    ? hit.distance_m
                             : pass.folded ? pass.path_m + hit.distance_m
                                           : (query.origin_world - queries_[pass.ray].origin_world).norm() +
                                                 hit.distance_m;
      const double cos_incidence = -hit.normal_world.dot(query.dir_world);
      const Material& material = scene_.material(hit.material_id);
      const double t = transmittance_[static_cast<std::size_t>(hit.material_id)];
      if (static_cast<std::size_t>(return_counts_[firing]) < return_capacity_) {
        SurfaceReturn& r = returns_[firing * return_capacity_ + static_cast<std::size_t>(return_counts_[firing]++)];
        r.range_m = range_m;
        r.retroreflective = material.retroreflective;
        r.cos_incidence = cos_incidence;
        r.power = (cos_incidence < cos_grazing_cutoff_ || cos_incidence <= 0.0)
                      ? 0.0
                      : pattern_[pass.ray % k_rays].weight * pass.path_t * pass.path_t * material.albedo *
                            cos_incidence * std::exp(-config_.intensity_attenuation_per_m * range_m);
      }
      if (depth + 1 >= config_.max_surfaces_per_ray || range_m + kPassThroughM >= config_.max_range_m) continue;
      const double left_m = config_.max_range_m - range_m - kPassThroughM;
      if (t > 0.0) {
        next_info_.push_back({pass.ray, pass.path_t * t, range_m + kPassThroughM, pass.folded});
        next_queries_.push_back(
            RayQuery{query.origin_world + (hit.distance_m + kPassThroughM) * query.dir_world, query.dir_world, left_m});
      }
      if (config_.specular_reflections && material.specular > 0.0 && cos_incidence > 0.0) {
        // Mirror: d' = d - 2 (d . n) n, restarting just off the surface on the incoming side.
        const Eigen::Vector3d p = query.origin_world + hit.distance_m * query.dir_world;
        const Eigen::Vector3d d = query.dir_world + 2.0 * cos_incidence * hit.normal_world;
        next_info_.push_back({pass.ray, pass.path_t * material.specular, range_m + kPassThroughM, true});
        next_queries_.push_back(RayQuery{p + kPassThroughM * d, d, left_m});
      }
    }
    if (next_queries_.empty()) break;
    pass_queries_.swap(next_queries_);
    pass_info_.swap(next_info_);
    pass_hits_.resize(pass_queries_.size());
    scene_.IntersectBatch(pass_queries_.data(), pass_queries_.size(), pass_hits_.data());
    queries = pass_queries_.data();
    hits = pass_hits_.data();
    n = pass_queries_.size();
  }
  if (!retro_spheres_.empty()) AddBloom(n_firings);
}

// Forms the firing's echoes, picks the reported ones, adds noise and writes the wire fields (and *truth, when
// not null).
void Vlp16Caster::Measure(const Firing& firing, std::size_t firing_index, int laser_id, Vlp16FiringSequence* seq,
                          LidarTruthPoint* truth) {
  const bool dual = config_.return_mode == Vlp16ReturnMode::kDual;
  // Unit normals, one per firing (two in dual mode) whether or not it returns; scaled by each echo's sigma.
  double unit_noise[2] = {StandardNormal(&range_rng_), 0.0};
  if (dual) unit_noise[1] = StandardNormal(&range_rng_);
  const std::size_t capacity = return_capacity_;
  if (truth) {
    const RayHit& central = hits_[QueryIndex(firing_index, 0)];
    *truth = LidarTruthPoint();
    truth->t_s = firing.t_s;
    truth->laser_id = static_cast<uint8_t>(laser_id);
    truth->hit = central.hit;
    truth->origin_world = firing.origin_world;
    truth->dir_world = firing.dir_world;
    if (central.hit) {
      truth->true_range_m = central.distance_m;
      truth->object_id = central.object_id;
      truth->p_world = firing.origin_world + central.distance_m * firing.dir_world;
    }
  }
  echoes_.clear();
  const std::size_t n_returns = static_cast<std::size_t>(return_counts_[firing_index]);
  const SurfaceReturn* first = &returns_[firing_index * capacity];
  if (n_returns == 1 && first->power > 0.0) {  // the common case of a single surface: one echo, nothing to merge
    echoes_.push_back(Echo{first->range_m, first->power, first->retroreflective, first->cos_incidence});
  } else {
    FormEchoes(&returns_[firing_index * capacity], n_returns, config_.echo_separation_m, &echoes_);
  }
  const EchoChoice choice = ChooseEchoes(echoes_, config_.return_mode, config_.min_intensity_for_return,
                                         config_.min_range_m, config_.max_range_m);
  const int slots[2] = {choice.primary, dual ? choice.secondary : -1};
  uint16_t distance[2] = {0, 0};
  uint8_t reflectivity[2] = {0, 0};
  for (int s = 0; s < 2; ++s) {
    if (slots[s] < 0) continue;
    const Echo& e = echoes_[static_cast<std::size_t>(slots[s])];
    const double p = std::min(e.power, 1.0);
    const long long byte = e.retroreflective ? 101 + static_cast<long long>(154.0 * p + 0.5)
                                             : static_cast<long long>(100.0 * p + 0.5);
    const int byte_clamped = static_cast<int>(std::clamp<long long>(byte, 0, 255));
    // One echo reported twice (dual mode, single echo) is one measurement: identical blocks (manual 9.3.2).
    const double noise_m = RangeSigma(e) * unit_noise[s == 1 && slots[1] == slots[0] ? 0 : s];
    const double measured_m = e.range_m + RangeBias(byte_clamped) + noise_m;
    if (measured_m < config_.min_range_m || measured_m > config_.max_range_m) continue;
    const long long units = static_cast<long long>(measured_m / kVlp16DistanceUnitM + 0.5);  // > 0: rounds
    if (units <= 0 || units > 65535) continue;
    distance[s] = static_cast<uint16_t>(units);
    reflectivity[s] = static_cast<uint8_t>(byte_clamped);
    if (truth) truth->echo_range_m[static_cast<std::size_t>(s)] = e.range_m;
  }
  if (truth) {
    truth->returned = distance[0] != 0;
    truth->returned2 = dual && distance[1] != 0;
  }
  seq->distance_2mm[laser_id] = distance[0];
  seq->reflectivity[laser_id] = reflectivity[0];
  seq->distance2_2mm[laser_id] = dual ? distance[1] : distance[0];
  seq->reflectivity2[laser_id] = dual ? reflectivity[1] : reflectivity[0];
}

void Vlp16Caster::Fire(int num_sequences, const PoseFn& T_world_lidar_at, std::vector<Vlp16FiringSequence>* out,
                       std::vector<LidarTruthPoint>* truth_out) {
  ROTOLIDAR_CHECK(out != nullptr, "Fire needs an output");
  ROTOLIDAR_CHECK(num_sequences >= 0, "num_sequences = " << num_sequences);
  ReserveGeometric(out, static_cast<std::size_t>(num_sequences));
  if (truth_out) ReserveGeometric(truth_out, static_cast<std::size_t>(num_sequences) * kLasers);
  for (int done = 0; done < num_sequences; done += kSequencesPerBatch) {
    const int n_seq = std::min(kSequencesPerBatch, num_sequences - done);
    const std::size_t first = out->size();
    out->resize(first + static_cast<std::size_t>(n_seq));
    batch_sequences_ = static_cast<std::size_t>(n_seq);
    for (int s = 0; s < n_seq; ++s) {
      const bool last_in_call = done + s + 1 == num_sequences;
      PlanSequence(T_world_lidar_at, &(*out)[first + s], static_cast<std::size_t>(s), last_in_call);
    }
    CastBatch(static_cast<std::size_t>(n_seq) * kLasers);
    for (int s = 0; s < n_seq; ++s) {
      for (int i = 0; i < kLasers; ++i) {
        const std::size_t f = static_cast<std::size_t>(s) * kLasers + i;
        LidarTruthPoint* truth = truth_out ? &truth_out->emplace_back() : nullptr;
        Measure(firings_[f], f, i, &(*out)[first + s], truth);
      }
    }
  }
}

}  // namespace rotolidar::sim
