#pragma once
// A simulated Velodyne HDL-64E S2 as KITTI's car carried it (Geiger, Lenz, Stiller, Urtasun, "Vision meets
// robotics: The KITTI dataset", IJRR 2013; Velodyne HDL-64E S2 user's manual and datasheet). It produces point
// clouds, not packets: one revolution = the points of KITTI's velodyne bins (x y z reflectance in the LiDAR frame),
// each point measured from the LiDAR pose at its own firing time (no motion compensation).
//
// Lasers: 64, in two blocks of 32 (Hdl64ElevationDeg): upper block +2.0 .. -8.33 deg in 1/3 deg steps, lower block
// -8.83 .. -24.33 deg in 1/2 deg steps (the HDL-64E S2's nominal +2 .. -24.8 deg vertical field of view; the
// per-laser spacing is the one measured on KITTI 00's bins, docs/kitti.md). Laser 0 is the top one.
// Sweep: azimuth a = atan2(y, x) of the LiDAR frame (x forward, y left, z up) grows from 0 at the revolution start
// through 360 deg, in firings_per_revolution equal steps (all 64 lasers of a column fire at the column's time:
// the S2 fires its lasers within ~50 us, 1.5 mm of car travel at 30 m/s, neglected). This is the order KITTI's bins
// store each scan line in (counter-clockwise, from straight ahead), which the core's KITTI reader takes as the
// firing order. Ray origin = the LiDAR origin (the lasers' few-cm offsets on the head are not modelled).
// Per point: range = first hit of the ray + N(0, range_noise_sigma_m), reported along the laser's direction
// (with elevation_error_deg added to its elevation); a ray that hits nothing within max_range_m,
// a measured range outside [min_range_m, max_range_m], incidence beyond grazing_cutoff_deg or a reflectance under
// min_reflectance gives no point. Reflectance = albedo * cos(incidence) * exp(-attenuation * range), in [0, 1].
// Dynamic objects: the scene is moved to the chunk's time (EmbreeScene::SetTime) before each chunk of
// columns_per_chunk columns.
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/types/geometry.hpp"
#include "core/types/time.hpp"
#include "core/util/rng.hpp"
#include "sim/world/embree_scene.hpp"

namespace rotolidar::sim {

inline constexpr int kHdl64Lasers = 64;

/// Nominal elevation of laser `laser` (0 = top .. 63 = bottom) [deg]; laser outside 0..63 is a programmer error.
double Hdl64ElevationDeg(int laser);

struct Hdl64CasterConfig {
  double revolution_hz = 10.0;       ///< head spin [Hz] (KITTI: 10 Hz)
  /// Firing columns per revolution. KITTI 00's bins step 0.179 deg in azimuth per point (median over every line
  /// of frame 0, ~2010 points a line): the S2's 1.3 M points/s at 10 Hz. The datasheet's 0.09 deg is at 5 Hz.
  int firings_per_revolution = 2000;
  /// Range noise, 1 sigma [m]: the HDL-64E datasheet's accuracy "< 2 cm (1 sigma)"; 0 = noise-free.
  double range_noise_sigma_m = 0.02;
  double min_range_m = 0.9;          ///< shorter measured ranges give no point [m]
  double max_range_m = 120.0;        ///< rated range (datasheet); also the ray length [m]
  /// Incidence angles above this give no point. 88 deg keeps flat ground out to ~50 m for lasers at -2 deg and
  /// below, where the reflectance threshold ends dark asphalt anyway (albedo 0.18: cos(incidence) > 0.055).
  double grazing_cutoff_deg = 88.0;
  double min_reflectance = 0.01;     ///< weaker returns give no point
  double intensity_attenuation_per_m = 0.004;  ///< residual range falloff of the reflectance
  /// Intrinsic vertical-angle error [deg]: every point is reported at its laser's elevation + this (the ray is
  /// cast at the true one), bending flat ground into a shallow cone. IMLS-SLAM (Deschaud, ICRA 2018) found
  /// KITTI's bins need a 0.22 deg correction of this kind. 0 = a perfectly calibrated sensor.
  double elevation_error_deg = 0.0;
  int columns_per_chunk = 50;        ///< columns cast per Embree batch (and per SetTime of dynamic objects)
  /// True when usable; otherwise false with the field named in *error.
  bool Validate(std::string* error) const;
};

/// One point of a revolution, in the LiDAR frame at its own firing time.
struct Hdl64Point {
  float x_m = 0.f, y_m = 0.f, z_m = 0.f;
  float reflectance = 0.f;  ///< [0, 1]
  float t_s = 0.f;          ///< firing time after the revolution start [s], in [0, 1 / revolution_hz)
  uint8_t laser = 0;        ///< 0 = top
};

/// Deterministic for a given (scene, config, run_seed, call sequence): the stream "hdl64.range" draws one normal
/// per ray (hit or not). Not thread-safe; the scene must outlive the caster.
class Hdl64Caster {
 public:
  /// Throws InternalError (a programmer error) when config.Validate fails: validate at the edges.
  Hdl64Caster(EmbreeScene* scene, const Hdl64CasterConfig& config, uint64_t run_seed);

  /// Casts one revolution starting at t0_s (azimuth 0) with T_world_lidar_at(t) called once per column, times
  /// non-decreasing. *out gets the points laser by laser, top laser first, each laser in firing order (KITTI's bin
  /// layout); replaced, not appended.
  void Revolution(Seconds t0_s, const std::function<Pose3(Seconds)>& T_world_lidar_at, std::vector<Hdl64Point>* out);

  /// Unit direction of laser `laser` at azimuth `azimuth_rad` in the LiDAR frame.
  static Eigen::Vector3d RayDirection(int laser, double azimuth_rad);
  Seconds period_s() const { return 1.0 / config_.revolution_hz; }
  const Hdl64CasterConfig& config() const { return config_; }

 private:
  void CastChunk(Seconds t0_s, int first_column, int columns, const std::function<Pose3(Seconds)>& pose_at);

  EmbreeScene* scene_;
  Hdl64CasterConfig config_;
  RandomStream range_rng_;
  double cos_grazing_cutoff_ = 0.0;
  std::array<Eigen::Vector3d, kHdl64Lasers> dir0_{};  ///< directions at azimuth 0
  std::array<Eigen::Vector3d, kHdl64Lasers> reported0_{};  ///< reported directions at azimuth 0 (elevation error)
  std::vector<RayQuery> queries_;                   ///< laser-major within a chunk
  std::vector<RayHit> hits_;
  std::vector<Eigen::Vector3d> dir_lidar_;          ///< per query
  std::array<std::vector<Hdl64Point>, kHdl64Lasers> lines_;  ///< the revolution being cast, per laser
};

}  // namespace rotolidar::sim
