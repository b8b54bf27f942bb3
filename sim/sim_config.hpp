#pragma once
// Configuration of one simulation run: the scene, the rig model, how its carrier moves, the motor drive, and the
// sensors. Plain structs with defaults; YAML I/O at the edge (LoadSimConfig / EmitSimConfig). Unknown keys are
// errors naming file:line. The sections reuse each module's own parser (rig_model, carrier, motor, imu).
#include <cstdint>
#include <string>
#include <vector>

#include "core/wire/vlp16.hpp"
#include "core/types/calib.hpp"
#include "sim/camera/camera_model.hpp"
#include "sim/faults/faults.hpp"
#include "sim/lidar/vlp16_caster.hpp"
#include "sim/rig/carrier_paths.hpp"
#include "sim/rig/rig_errors.hpp"
#include "sim/rig/rig_model.hpp"
#include "sim/realism.hpp"
#include "sim/rig/stepper.hpp"
#include "sim/sensors/imu_model.hpp"
#include "sim/sensors/sensor_clock.hpp"
#include "sim/truth/clock_truth.hpp"

namespace YAML {
class Emitter;
class Node;
}

namespace rotolidar::sim {

/// Sensor clocks relative to the rig clock, for fault studies (all off by default: no offset, no drift, PPS
/// synced, no capture jitter). Each clock stamps t + offset + drift_ppm * 1e-6 * t (SensorClock); the IMU's clock
/// lives in ImuErrorConfig (imu_clock_offset_s, imu_clock_drift_ppm). calib.yaml holds only lidar_offset_s (the
/// nominal value the rig's owner knows); truth/clocks.yaml holds every clock as run (TrueClocks()).
struct ClockConfig {
  double lidar_offset_s = 0.0;    ///< VLP-16 clock: sensor time = rig time - lidar_offset_s (calib.yaml's sign)
  double lidar_drift_ppm = 0.0;   ///< VLP-16 clock rate error [ppm]; applies only when !lidar_pps_synced
  bool lidar_pps_synced = true;   ///< true: the PPS disciplines the head's clock (no drift); false: free-running
  double encoder_offset_s = 0.0;  ///< encoder stamps written = true rig time + encoder_offset_s (+ drift)
  double encoder_drift_ppm = 0.0;
  double camera_offset_s = 0.0;   ///< camera.csv stamps = true mid-exposure time + camera_offset_s (+ drift)
  double camera_drift_ppm = 0.0;
  CaptureJitterConfig lidar_capture;  ///< host receive latency and jitter of the pcap capture times

  /// The head's clock in SensorClock's sign (0.0 - x: a zero offset is +0, not -0).
  SensorClock Lidar() const { return {0.0 - lidar_offset_s, lidar_pps_synced ? 0.0 : lidar_drift_ppm}; }
  SensorClock Encoder() const { return {encoder_offset_s, encoder_drift_ppm}; }
  SensorClock Camera() const { return {camera_offset_s, camera_drift_ppm}; }
  /// False naming the field ("clocks.<key>") unless finite, |offset| <= 1 s, |drift| <= 1000 ppm and the
  /// capture latency and jitter scale in [0, 0.01] s.
  bool Validate(std::string* error) const;
};

struct SimConfig {
  uint64_t seed = 1;                 ///< run seed: every random stream derives from it plus its name
  /// The preset the error sources started from (ApplyRealism); the struct's own defaults are kIdeal. In YAML,
  /// `realism:` is applied first, then the file's other keys override single sources.
  Realism realism = Realism::kIdeal;
  double duration_s = 20.0;          ///< simulated time [s]
  std::string scene = "box_room";    ///< a name in scenes/ (scenes/<name>.yaml) or a path to a scene file
  double truth_rate_hz = 1000.0;     ///< rate of base/lidar/rotor truth samples [Hz] (the physics rate)
  Vlp16ReturnMode return_mode = Vlp16ReturnMode::kStrongest;
  RigModelConfig rig_model;          ///< the MuJoCo rig: platform, motor axis, masses, sites, physics step
  CarrierConfig carrier;             ///< how the base moves (a target the physics body tracks)
  MotorDriveConfig motor;            ///< command profile, stepper, closed-loop PID, encoder
  ImuConfig imu;                     ///< IMU noise (TRUE values) and per-run errors
  Vlp16CasterConfig lidar;
  LidarIntrinsics lidar_intrinsics;  ///< the VLP-16's laser table (manual's values by default)
  ClockConfig clocks;
  CameraConfig camera;               ///< the RGB camera (sim/camera/camera_model.hpp); on by default at 30 Hz
  /// Rig imperfections (sim/rig/rig_errors.hpp): calibration errors in calib.yaml, axis wobble, rotor
  /// vibration at the IMU. All off by default; YAML `rig_errors:` (emitted only when enabled).
  RigErrorConfig rig_errors;
  /// Injected faults (sim/faults/faults.hpp): lost, duplicated, reordered or blinded LiDAR packets, a frozen
  /// encoder, IMU dropouts and saturation. All off by default; YAML `faults:` (emitted only when any is on).
  FaultConfig faults;
  /// true: the run takes the scene's default carrier (sim/scene_carrier.hpp ChooseSceneCarrier: its handheld
  /// path, else its first path, else the scripted loop if that fits) and carrier.type is ignored. The CLI sets
  /// it unless --carrier or a config file's carrier.type names one; a config file with carrier.type clears it.
  /// Not a YAML key: the resolved config of a run (sim_config.yaml) names the carrier that was chosen.
  bool carrier_from_scene = false;

  bool Validate(std::string* error) const;
  /// The rig's TRUE calibration (what the sim simulates with; calib.yaml holds BelievedCalib(), equal to this
  /// unless rig_errors.calibration is on or the IMU clock has an offset): geometry from rig_model, IMU noise,
  /// encoder resolution and zero, the nominal motor speed (the uniform-rotation fallback), the nominal LiDAR clock
  /// offset, the IMU clock's offset at rig time 0 and the camera's lens and rate (T_base_cam is the rig model's
  /// `cam` site).
  RigCalib TrueCalib() const;
  /// What calib.yaml holds: TrueCalib() with the run's calibration errors (rig_errors.calibration, drawn from
  /// the seed's "calib.error" stream) applied, and imu_time_offset_s 0 (the IMU clock's error is not known).
  RigCalib BelievedCalib() const;
  /// Every sensor clock as the run applies it (written to truth/clocks.yaml).
  ClockTruth TrueClocks() const;
};

/// Sets every error source the presets govern to preset r's values (docs/noise_models.md, "Realism presets"):
/// rig imperfections (rig_errors), sensor clocks, IMU scale/misalignment/clock errors, the VLP-16's spin jitter. Other fields (scene, carrier,
/// motor, seed, durations) are untouched. ApplyRealism(kIdeal) restores the struct's defaults for those fields.
void ApplyRealism(Realism r, SimConfig* config);

/// The built-in default: the seed's forward-scanning rig (motor axis along base +x, the VLP-16's spin axis
/// across it), handheld through the box room at walking speed, motor at 2.6 rad/s (docs/motor_model.md).
SimConfig DefaultSimConfig();

/// DefaultSimConfig() with preset r applied: what `sim`, `demo`, studies and scenario tests start from
/// (kTypical there; DefaultSimConfig() itself is kIdeal).
SimConfig PresetSimConfig(Realism r);

/// The rig geometry of the default rig (docs/frames.md draws it).
RigCalib DefaultRigCalib();

/// Resolves `scene` to a file: an existing regular file is used as is; otherwise <scenes_dir>/<scene>.yaml, with
/// scenes_dir from $ROTOLIDAR_SCENES or the source tree's scenes/.
std::string ResolveScenePath(const std::string& scene);

/// Names of the scene files (*.yaml, without the extension) in the scenes folder ResolveScenePath uses, sorted.
std::vector<std::string> AvailableScenes();

/// ResolveScenePath; fails when no such file exists, listing AvailableScenes() in the message.
Status FindSceneFile(const std::string& scene, std::string* path);

/// Reads a YAML file whose keys override *config (only the keys given change); a `realism:` key first applies
/// that preset (ApplyRealism), then the file's other keys. `rig_model` may be a
/// mapping of overrides or a path to a rig parameter file (relative paths resolve against the config's folder).
Status LoadSimConfig(const std::string& path, SimConfig* config);
/// LoadSimConfig on an already-parsed mapping (e.g. a section of a study file): `path` names it in messages
/// (file:line from the node's marks) and resolves relative paths. *config is untouched on error.
Status ParseSimConfig(const std::string& path, const YAML::Node& root, SimConfig* config);
/// Writes every field: the resolved config of a run.
void EmitSimConfig(YAML::Emitter& out, const SimConfig& config);

}  // namespace rotolidar::sim
