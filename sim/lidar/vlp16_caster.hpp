#pragma once
// The simulated VLP-16 head: keeps the firing schedule (VLP-16 user manual 63-9243, section 9.4), casts each laser's beam
// into the EmbreeScene from the lidar pose at that laser's own firing time, and produces the firing sequences the
// packet encoder turns into wire bytes, plus per-firing ground truth for the bench. Every model and the source of
// its numbers: docs/lidar_model.md.
//
// Schedule: sequence k (counted from construction, across Fire calls) starts at t0_s + k * 55.296 us; laser i of
// it fires at + i * 2.304 us. The head azimuth a(t) grows at the spin rate (rpm, optionally with a seeded,
// slowly varying speed error); a sequence's azimuth_centideg is a(t_k) rounded to 0.01 deg, while each ray is
// cast at the exact a(t_k + i * 2.304 us), which the decoder's interpolation between sequences reproduces.
// Central ray of laser i in the lidar frame: origin Vlp16RayOrigin(offset_i) + r * Vlp16RayDirection(elev_i, a)
// (shared with the decoder in core/wire/vlp16.hpp). Pose: T_world_lidar at each firing time, exactly
// (pose_per_firing) or interpolated between exact poses at most 55.296 us apart (the sequence starts around it;
// the default, measured against the exact poses in tests/sim/lidar/vlp16_caster_test.cpp).
//
// Beam and echoes (vlp16_echoes.hpp): beam_rings = 0 casts the central ray only; > 0 samples the divergent beam
// with sub-rays, so a spot straddling an edge returns a mixed (power-weighted) range or two echoes >= 1 m apart.
// Transmissive materials (glass) pass part of the power on to the surfaces behind them; with specular_reflections
// mirrors send it on along the reflected direction (range = folded path). Blooming adds a weak retroreflective
// return to firings passing near a retroreflector.
// Range model: each reported echo's range + range_bias(reflectivity byte) + N(0, sigma(range, incidence,
// power)), quantised to 2 mm (sigma = range_noise_sigma_m with the defaults). No return (distance 0)
// when nothing is hit within max_range_m, the range is outside [min_range_m, max_range_m], every contributing
// surface is beyond grazing_cutoff_deg, or the echo's intensity 100 * power falls under min_intensity_for_return.
// Reflectivity byte of an echo of power s (in [0, 1]): diffuse round(100 s) (0..100; the VLP-16 calibrates out
// 1/r^2), retroreflective 101 + round(154 s) (101..255), with per surface s = albedo * cos(incidence) *
// exp(-intensity_attenuation_per_m * r) times the sub-ray's beam weight.
// Return mode: single modes put the strongest / last echo in distance_2mm; dual mode puts the last echo there and
// the strongest (the second strongest when the strongest is the last) in distance2_2mm, identical when there is
// only one echo (manual 9.3.2). In single modes distance2_2mm repeats distance_2mm.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/wire/vlp16.hpp"
#include "core/types/calib.hpp"
#include "core/types/geometry.hpp"
#include "core/util/rng.hpp"
#include "sim/lidar/vlp16_echoes.hpp"
#include "sim/world/embree_scene.hpp"

namespace rotolidar::sim {

struct Vlp16CasterConfig {
  double t0_s = 0.0;             ///< firing time of laser 0 of sequence 0 on the rig clock [s]
  double azimuth0_deg = 0.0;     ///< head azimuth at t0_s [deg], clockwise from lidar +x seen from above
  double rpm = 600.0;            ///< nominal head spin, [300, 1200] (the sensor itself sets steps of 60)
  /// Relative spin-rate error (1-sigma), a first-order Gauss-Markov process with correlation time
  /// rpm_jitter_tau_s (real heads drift slowly, 9-11 Hz reported at a 10 Hz setting). 0 = exact rpm.
  double rpm_jitter_frac = 0.0;
  double rpm_jitter_tau_s = 0.5;
  /// Gaussian range noise, 1-sigma [m]. The datasheet's "+-3 cm typical accuracy" read conservatively as 1-sigma
  /// (Gazebo's plugin uses 0.008 m); set 0 for noise-free truth tests.
  double range_noise_sigma_m = 0.03;
  /// Range-, incidence- and reflectivity-dependent noise (docs/lidar_model.md, section 5). The 1-sigma of an
  /// echo at range r, incidence theta and power p (0..1 scale) is
  ///   sqrt(s0^2 + (range_noise_per_m * r)^2) / max(cos theta, range_noise_min_cos)^range_noise_incidence_exponent
  ///   * min(range_noise_weak_max_gain, sqrt(range_noise_weak_power / p))   [the last factor only when p < it]
  /// with s0 = range_noise_sigma_m. The defaults (0, 0, 0) give s0 everywhere, exactly.
  double range_noise_per_m = 0.0;               ///< s1 [m per m of range]
  double range_noise_incidence_exponent = 0.0;  ///< k (0 = no incidence dependence)
  double range_noise_min_cos = 0.1;             ///< c_min, caps the incidence factor at c_min^-k
  double range_noise_weak_power = 0.0;          ///< diffuse echoes weaker than this are noisier; 0 = off
  double range_noise_weak_max_gain = 3.0;       ///< cap of the weak-echo factor (>= 1)
  /// Range walk: bias [m] added to every reported range as a function of the echo's reflectivity byte, piecewise
  /// linear through [byte, bias_m] points with increasing bytes, constant beyond the ends; empty = none.
  std::vector<std::array<double, 2>> range_bias_curve;
  /// Retroreflector blooming: a firing whose central ray passes within this half-angle [mrad] of a visible
  /// retroreflective surface also gets a return from it (power bloom_power_fraction times the surface's own);
  /// 0 = off. Only static retroreflectors bloom.
  double bloom_halo_mrad = 0.0;
  double bloom_power_fraction = 0.05;
  /// Materials with `specular` > 0 (scene file) send that fraction of a beam on along the mirrored direction; an
  /// echo from behind the mirror reports the folded path length (a ghost point). false = mirrors are plain
  /// diffuse surfaces (their specular fraction is ignored).
  bool specular_reflections = false;
  double min_range_m = 0.4;      ///< same for all lasers (the manual gives no per-laser minimum)
  double max_range_m = 100.0;    ///< rated range; also the ray length cast; <= 131.07 (uint16 x 2 mm)
  double grazing_cutoff_deg = 85.0;          ///< incidence angles above this give no return
  double min_intensity_for_return = 1.0;     ///< on the 0..100 diffuse scale (100 * s); 1.0 drops albedo < 1 %
  double intensity_attenuation_per_m = 0.004;  ///< residual range falloff of the reported byte (CARLA's default)
  /// Which echoes the sequences carry; keep equal to the packet encoder's mode (SimConfig::return_mode).
  Vlp16ReturnMode return_mode = Vlp16ReturnMode::kStrongest;
  /// Beam footprint: 0 = central ray only (no divergence, no mixed points); n = 1..4 rings of sub-rays
  /// (7, 19, 37, 61 rays per firing; the cost grows accordingly).
  int beam_rings = 0;
  double beam_divergence_horizontal_mrad = 3.0;  ///< full angle, 1/e^2, along the scan (VLP-16 datasheet copies)
  double beam_divergence_vertical_mrad = 1.5;    ///< full angle, 1/e^2, across the scan
  /// Returns closer than this merge into one echo (the manual: both returns only for objects >= 1 m apart).
  double echo_separation_m = 1.0;
  /// Materials (by scene name) that pass a fraction of the power on, e.g. {"window_glass", 0.9}; a sub-ray meets
  /// at most max_surfaces_per_ray surfaces.
  std::vector<std::pair<std::string, double>> material_transmittance;
  int max_surfaces_per_ray = 3;
  /// true: T_world_lidar_at is called for every laser firing; false: at each sequence start, interpolated between.
  bool pose_per_firing = false;

  /// True when usable; otherwise false with the field named in *error.
  bool Validate(std::string* error) const;
  /// The range-physics part of Validate (noise model, range walk, blooming).
  bool ValidateRangePhysics(std::string* error) const;
};

/// Checks that every material_transmittance name exists among `materials` and that its albedo (the diffusely
/// reflected fraction) plus its transmittance is <= 1 (message names the material).
Status CheckCasterMaterials(const Vlp16CasterConfig& config, const std::vector<Material>& materials);

/// Ground truth of one laser firing (bench only). `hit`: the central ray met geometry within max_range_m (whether
/// or not the sensor reported it); `returned`: distance_2mm is non-zero; `returned2`: distance2_2mm is.
/// A decoded point of slot s lies at origin_world + echo_range_m[s] * dir_world, up to noise and quantisation.
struct LidarTruthPoint {
  Seconds t_s = 0.0;   ///< firing time
  uint8_t laser_id = 0;
  bool hit = false;
  bool returned = false;
  bool returned2 = false;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  ///< exact first hit of the central ray (valid when hit)
  double true_range_m = 0.0;  ///< of p_world from the laser's origin
  int object_id = -1;  ///< what p_world lies on: -1 the static world, k Scene::dynamic_objects[k] (valid when hit)
  Eigen::Vector3d origin_world = Eigen::Vector3d::Zero();  ///< the laser's origin at its firing time
  Eigen::Vector3d dir_world = Eigen::Vector3d::UnitX();    ///< unit central ray
  std::array<double, 2> echo_range_m{};  ///< noise-free range of the echo in slot 0 / 1 (0 = none)
};

/// Stateful: each Fire call continues the schedule (sequence counter, head azimuth, random streams) where the
/// previous one stopped. Deterministic for a given (scene, intrinsics, config, run_seed, call pattern): the
/// random stream "lidar.range" draws one value per firing (two in dual mode) and "lidar.rpm" one per sequence,
/// regardless of hits. The scene must outlive the caster. Not thread-safe (one caster per thread).
class Vlp16Caster {
 public:
  /// Throws InternalError (a programmer error) if config.Validate or CheckCasterMaterials fails: validate configs
  /// at the edges.
  Vlp16Caster(const EmbreeScene& scene, const LidarIntrinsics& intrinsics, const Vlp16CasterConfig& config,
              uint64_t run_seed);
  /// Holds a reference to the scene: a temporary would dangle.
  Vlp16Caster(EmbreeScene&&, const LidarIntrinsics&, const Vlp16CasterConfig&, uint64_t) = delete;

  /// Fires `num_sequences` sequences. T_world_lidar_at(t) is called with non-decreasing times between the first
  /// and the last firing time of this call: with pose_per_firing once per laser firing, otherwise once per
  /// sequence start plus once at the last firing. Appends to *out and (when not null) 16 truth points per sequence
  /// to *truth_out.
  void Fire(int num_sequences, const std::function<Pose3(Seconds)>& T_world_lidar_at,
            std::vector<Vlp16FiringSequence>* out, std::vector<LidarTruthPoint>* truth_out);

  /// Firing time of laser `laser_id` in sequence `sequence_index` (the schedule, exactly).
  Seconds FiringTime(int64_t sequence_index, int laser_id) const;
  int64_t sequences_fired() const { return next_sequence_; }
  const Vlp16CasterConfig& config() const { return config_; }
  int rays_per_firing() const { return static_cast<int>(pattern_.size()); }

 private:
  struct Firing {  // one laser shot awaiting its hits
    Seconds t_s;
    Eigen::Vector3d origin_world;
    Eigen::Vector3d dir_world;  // unit central ray
  };
  using PoseFn = std::function<Pose3(Seconds)>;
  /// Plans sequence `s` of the batch: firings_[16 s + i] and their queries.
  void PlanSequence(const PoseFn& T_world_lidar_at, Vlp16FiringSequence* seq, std::size_t s, bool last_in_call);
  // Queries are laid out laser-major ([laser][sequence][sub-ray]): neighbouring rays differ by one azimuth step
  // (0.2 deg) instead of 2 deg of elevation, which Embree's coherent stream traverses faster.
  std::size_t QueryIndex(std::size_t firing, std::size_t k) const {
    return ((firing % 16) * batch_sequences_ + firing / 16) * pattern_.size() + k;
  }
  std::size_t FiringOfQuery(std::size_t q) const {
    const std::size_t r = q / pattern_.size();
    return (r % batch_sequences_) * 16 + r / batch_sequences_;
  }
  /// pose_start_ / pose_next_ / pose_span_s_ of the sequence to plan.
  void SequencePoses(const PoseFn& T_world_lidar_at, bool last_in_call);
  void CastBatch(std::size_t n_firings);
  void Measure(const Firing& firing, std::size_t firing_index, int laser_id, Vlp16FiringSequence* seq,
               LidarTruthPoint* truth);
  void AdvanceSpinRate();

  const EmbreeScene& scene_;
  LidarIntrinsics intrinsics_;
  Vlp16CasterConfig config_;
  RandomStream range_rng_;
  RandomStream rpm_rng_;
  int64_t next_sequence_ = 0;
  double head_azimuth_deg_ = 0.0;   ///< at the start of the next sequence, in [0, 360)
  double spin_error_ = 0.0;         ///< Gauss-Markov state, unit variance
  double spin_rate_degps_ = 0.0;    ///< during the next sequence
  double cos_grazing_cutoff_ = 0.0;
  std::array<double, 16> cos_elevation_{}, sin_elevation_{};
  std::vector<BeamSample> pattern_;
  std::vector<double> transmittance_;  ///< per material id (0 = opaque)
  bool any_transmissive_ = false;
  // Interpolation mode: the pose at the start of the sequence being planned and pose_span_s_ later (the next
  // sequence's start, or this sequence's last firing at the end of a Fire call).
  bool have_next_pose_ = false;
  Pose3 pose_start_ = Pose3::Identity(), pose_next_ = Pose3::Identity();
  double pose_span_s_ = kVlp16SequencePeriodS;
  // Per-batch scratch, reused across calls: firings, queries (pattern_.size() per firing), and the surface
  // returns of each firing (capacity rays * max_surfaces_per_ray each).
  std::size_t batch_sequences_ = 1;  ///< sequences in the batch being cast
  std::vector<Firing> firings_;
  std::vector<RayQuery> queries_;
  std::vector<RayHit> hits_;
  std::vector<SurfaceReturn> returns_;
  std::vector<int> return_counts_;
  std::vector<RayQuery> pass_queries_, next_queries_;  ///< sub-rays continuing behind transmissive surfaces
  std::vector<RayHit> pass_hits_;
  struct Pass {
    std::size_t ray;  ///< sub-ray index in the batch
    double path_t;    ///< one-way power factor so far (transmittances, specular fractions)
    double path_m;    ///< folded paths (after a mirror): the path length to the new origin; else unused
    bool folded;
  };
  std::vector<Pass> pass_info_, next_info_;
  /// Returns stored per firing: sub-rays * max_surfaces_per_ray (+ 1 bloom return when blooming is on).
  std::size_t return_capacity_ = 0;
  double RangeSigma(const Echo& e) const;
  double RangeBias(int reflectivity_byte) const;
  void AddBloom(std::size_t n_firings);
  struct RetroSphere {
    Eigen::Vector3d center;
    double radius_m;
  };
  std::vector<RetroSphere> retro_spheres_;
  std::vector<BeamSample> halo_pattern_;
  std::vector<RayQuery> halo_queries_;
  std::vector<RayHit> halo_hits_;
  std::vector<std::size_t> halo_firings_;
  std::vector<Echo> echoes_;
};

}  // namespace rotolidar::sim
