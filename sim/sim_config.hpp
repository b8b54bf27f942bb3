#pragma once
// Configuration of one simulation run: the scene, the rig, its motion and its sensors. Plain structs with
// defaults; YAML I/O at the edge (LoadSimConfig / EmitSimConfig). Unknown keys are errors naming file:line.
#include <cstdint>
#include <string>

#include "core/io/vlp16.hpp"
#include "core/types/calib.hpp"
#include "sim/lidar/vlp16_caster.hpp"
#include "sim/rig/base_motion.hpp"
#include "sim/rig/motor.hpp"
#include "sim/sensors/imu_model.hpp"

namespace YAML {
class Emitter;
}

namespace rotolidar::sim {

struct SimConfig {
  uint64_t seed = 1;                 ///< run seed: every random stream derives from it plus its name
  double duration_s = 20.0;          ///< simulated time [s]
  std::string scene = "box_room";    ///< a name in scenes/ (scenes/<name>.yaml) or a path to a scene file
  double truth_rate_hz = 200.0;      ///< rate of base/lidar/rotor/bias truth samples [Hz]
  Vlp16ReturnMode return_mode = Vlp16ReturnMode::kStrongest;
  RigCalib rig;                      ///< the TRUE rig geometry and sensor parameters (written to calib.yaml)
  ScriptedBaseMotionConfig motion;
  MotorConfig motor;
  EncoderConfig encoder;
  ImuBiasConfig imu_bias;
  Vlp16CasterConfig lidar;

  bool Validate(std::string* error) const;
};

/// The built-in default: the seed's forward-scanning rig (motor axis along base +x, the VLP-16's spin axis
/// across it), handheld through the box room at walking speed, motor at 2.6 rad/s.
SimConfig DefaultSimConfig();

/// The rig geometry of the default rig (docs/frames.md draws it).
RigCalib DefaultRigCalib();

/// Resolves `scene` to a file: an existing path is used as is; otherwise <scenes_dir>/<scene>.yaml, with
/// scenes_dir from $ROTOLIDAR_SCENES or the source tree's scenes/.
std::string ResolveScenePath(const std::string& scene);

/// Reads a YAML file whose keys override DefaultSimConfig() (only the keys given change).
Status LoadSimConfig(const std::string& path, SimConfig* config);
/// Writes every field: the resolved config of a run.
void EmitSimConfig(YAML::Emitter& out, const SimConfig& config);

}  // namespace rotolidar::sim
