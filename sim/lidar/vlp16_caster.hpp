#pragma once
// The simulated VLP-16 head: keeps the firing schedule (../shared/docs/sensor_facts.md), casts each laser's ray
// into the EmbreeScene from the lidar pose at that laser's own firing time, and produces the firing sequences the
// packet encoder turns into wire bytes, plus per-ray ground truth for the bench.
//
// Schedule: sequence k (counted from construction, across Fire calls) starts at t0_s + k * 55.296 us; laser i of
// it fires at + i * 2.304 us. The head azimuth a(t) grows at the spin rate (rpm, optionally with a seeded,
// slowly varying speed error); a sequence's azimuth_centideg is a(t_k) rounded to 0.01 deg, while each ray is
// cast at the exact a(t_k + i * 2.304 us), which the decoder's interpolation between sequences reproduces.
// Ray of laser i in the lidar frame: origin Vlp16RayOrigin(offset_i) + r * Vlp16RayDirection(elev_i, a) (shared
// with the decoder in core/io/vlp16.hpp).
//
// Range model: r_meas = r_true + N(0, range_noise_sigma_m), quantised to 2 mm. No return (distance 0) when the
// ray hits nothing within max_range_m, r_meas is outside [min_range_m, max_range_m], the incidence angle exceeds
// grazing_cutoff_deg, or the diffuse intensity below falls under min_intensity_for_return.
// Reflectivity model (docs/scene_format.md): with theta the incidence angle and r the true range,
//   s = albedo * cos(theta) * exp(-intensity_attenuation_per_m * r)          (in [0, 1])
//   diffuse:          byte = round(100 * s)           (0..100; the VLP-16 calibrates out 1/r^2)
//   retroreflective:  byte = 101 + round(154 * s)     (101..255)
// Dual-return fields repeat the primary return.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/io/vlp16.hpp"
#include "core/types/calib.hpp"
#include "core/types/geometry.hpp"
#include "core/util/rng.hpp"
#include "sim/world/embree_scene.hpp"

namespace rotolidar::sim {

struct Vlp16CasterConfig {
  double t0_s = 0.0;             ///< firing time of laser 0 of sequence 0 on the rig clock [s]
  double azimuth0_deg = 0.0;     ///< head azimuth at t0_s [deg], clockwise from lidar +x seen from above
  double rpm = 600.0;            ///< nominal head spin (the VLP-16 allows 300..1200 in steps of 60)
  /// Relative spin-rate error (1-sigma), a first-order Gauss-Markov process with correlation time
  /// rpm_jitter_tau_s (real heads drift slowly, 9-11 Hz reported at a 10 Hz setting). 0 = exact rpm.
  double rpm_jitter_frac = 0.0;
  double rpm_jitter_tau_s = 0.5;
  /// Gaussian range noise, 1-sigma [m]. The datasheet's "+-3 cm typical accuracy" read conservatively as 1-sigma
  /// (Gazebo's plugin uses 0.008 m); set 0 for noise-free truth tests.
  double range_noise_sigma_m = 0.03;
  double min_range_m = 0.4;      ///< same for all lasers (the manual gives no per-laser minimum)
  double max_range_m = 100.0;    ///< rated range; also the ray length cast; <= 131.07 (uint16 x 2 mm)
  double grazing_cutoff_deg = 85.0;          ///< incidence angles above this give no return
  double min_intensity_for_return = 1.0;     ///< on the 0..100 diffuse scale (100 * s); 1.0 drops albedo < 1 %
  double intensity_attenuation_per_m = 0.004;  ///< residual range falloff of the reported byte (CARLA's default)

  /// True when usable; otherwise false with the field named in *error.
  bool Validate(std::string* error) const;
};

/// Ground truth of one ray (bench only). `hit`: the ray met geometry within max_range_m (whether or not the
/// sensor reported it); `returned`: the sequence carries a non-zero distance for it.
struct LidarTruthPoint {
  Seconds t_s = 0.0;   ///< firing time
  uint8_t laser_id = 0;
  bool hit = false;
  bool returned = false;
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  ///< exact hit point (valid when hit)
  double true_range_m = 0.0;  ///< from the laser's origin, before noise and quantisation
};

/// Stateful: each Fire call continues the schedule (sequence counter, head azimuth, random streams) where the
/// previous one stopped. Deterministic for a given (scene, intrinsics, config, run_seed, call pattern): the
/// random streams "lidar.range" and "lidar.rpm" draw one value per firing / per sequence regardless of hits.
/// The scene must outlive the caster. Not thread-safe (one caster per thread).
class Vlp16Caster {
 public:
  /// Throws InternalError (a programmer error) if config.Validate fails: validate configs at the edges.
  Vlp16Caster(const EmbreeScene& scene, const LidarIntrinsics& intrinsics, const Vlp16CasterConfig& config,
              uint64_t run_seed);

  /// Fires `num_sequences` sequences. T_world_lidar_at(t) is called once per laser firing, in time order.
  /// Appends to *out and (when not null) 16 truth points per sequence to *truth_out.
  void Fire(int num_sequences, const std::function<Pose3(Seconds)>& T_world_lidar_at,
            std::vector<Vlp16FiringSequence>* out, std::vector<LidarTruthPoint>* truth_out);

  /// Firing time of laser `laser_id` in sequence `sequence_index` (the schedule, exactly).
  Seconds FiringTime(int64_t sequence_index, int laser_id) const;
  int64_t sequences_fired() const { return next_sequence_; }
  const Vlp16CasterConfig& config() const { return config_; }

 private:
  struct Firing {  // one laser shot awaiting its hit
    Seconds t_s;
    Eigen::Vector3d origin_world;
    Eigen::Vector3d dir_world;
  };
  void PlanSequence(const std::function<Pose3(Seconds)>& T_world_lidar_at, Vlp16FiringSequence* seq,
                    Firing* firings);
  void Measure(const Firing& firing, const RayHit& hit, int laser_id, uint16_t* distance_2mm,
               uint8_t* reflectivity, LidarTruthPoint* truth);
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
};

}  // namespace rotolidar::sim
