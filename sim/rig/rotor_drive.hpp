#pragma once
// The seam between the rig's physics (sim/rig/rig_physics: MuJoCo integrates the rotor hinge) and whatever drives
// that hinge (sim/rig/stepper: the stepper motor, its driver and the closed-loop PID on the encoder).
//
// The physics calls the drive once per physics step, before integrating the step, with the TRUE hinge state. The
// drive answers the torque its motor applies to the rotor. A drive that reads an encoder (the stepper's PID) owns
// that encoder and samples it from these true states; what the encoder reports is also what the recording gets
// (DrainEncoderSamples), so the estimator sees exactly what the rig's controller saw.
#include <vector>

#include "core/types/messages.hpp"
#include "core/types/time.hpp"

namespace rotolidar::sim {

/// The TRUE state of the rotor hinge at one physics step (ground truth; never leaves sim/ except via truth/).
struct RotorJointState {
  Seconds t_s = 0.0;         ///< rig clock [s]
  double theta_rad = 0.0;    ///< unwrapped hinge angle about motor +z [rad] (T_base_rotor = T_base_motor * RotZ)
  double omega_radps = 0.0;  ///< d(theta)/dt [rad/s]
};

/// Interface for the rotor's motor. Stateful: Torque() is called with strictly increasing t_s, one call per
/// physics step of length dt_s. Not thread-safe.
class RotorDrive {
 public:
  virtual ~RotorDrive() = default;
  /// Torque [N m] the motor applies to the rotor about motor +z during the step [t_s, t_s + dt_s).
  virtual double Torque(const RotorJointState& state, double dt_s) = 0;
  /// Moves the encoder samples produced so far (stamped on the rig clock, in time order) into *out (appends).
  /// Drives without an encoder append nothing.
  virtual void DrainEncoderSamples(std::vector<EncoderSample>* out) { (void)out; }
};

}  // namespace rotolidar::sim
