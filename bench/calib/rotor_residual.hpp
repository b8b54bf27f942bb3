#pragma once
// The rotor calibration's parameters and its point-to-plane residual (docs/calibration.md).
//
// Parameters: a correction of the input calibration. T_rotor_lidar' = [ExpSO3(tilt) * R, t + lever] (the
// rotation composed on the left, in the rotor frame, as the twin draws its errors: sim/rig/rig_errors.hpp) and
// encoder zero' = zero + encoder_zero, so theta' = theta - encoder_zero, and the LiDAR's clock offset' = offset +
// time_offset (a point fired at t takes the encoder's angle at t + time_offset, to first order theta + omega *
// time_offset). The rotation correction is a rotation vector around the input rotation: an exact chart of SO(3)
// near it (the corrections are far below pi).
//
// Residual of one point q against the plane of its neighbours j (seen half a revolution away), all in the motor
// frame (T_base_motor is common to every point and cancels out of the differences):
//   P(i) = RotZ(theta_i - encoder_zero + omega_i time_offset) * (ExpSO3(tilt) * u_i + t + lever),  u_i = R p_lidar_i
//   r    = n . (P(q) - mean_j P(j))
// n: the unit normal of the neighbours (PCA), fixed while Ceres solves, refitted with the association.
#include <array>
#include <cmath>
#include <vector>

#include <ceres/rotation.h>
#include <Eigen/Core>

#include "core/types/calib.hpp"

namespace rotolidar::bench {

/// Indices of the calibration parameters (lever arm and tilt in the rotor frame, the encoder zero, the LiDAR's
/// time offset against the encoder).
enum CalibParam {
  kLeverX = 0, kLeverY, kLeverZ, kTiltX, kTiltY, kTiltZ, kEncoderZero, kTimeOffset, kCalibParamCount
};
/// "lever_x_m", ..., "tilt_x_rad", ..., "encoder_zero_rad", "time_offset_s".
const char* CalibParamName(int param);

/// A correction of the input calibration (file comment).
struct RotorCalibParams {
  std::array<double, 3> lever_m{0, 0, 0};   ///< added to T_rotor_lidar's translation (rotor frame) [m]
  std::array<double, 3> tilt_rad{0, 0, 0};  ///< rotation vector composed on the left of T_rotor_lidar's [rad]
  double encoder_zero_rad = 0.0;            ///< added to the encoder zero offset [rad]
  double time_offset_s = 0.0;               ///< added to calib.yaml's lidar_clock_offset_s [s]
  double Get(int param) const;
  void Set(int param, double value);
};

/// `calib` with the correction applied.
RigCalib ApplyCorrection(const RigCalib& calib, const RotorCalibParams& correction);

/// One point prepared for the residual: u = R_rotor_lidar (input) * p_lidar, its rotor angle's cos / sin and the
/// rotor speed there.
struct ResidualPoint {
  double u[3] = {0, 0, 0};
  double cos_theta = 1.0, sin_theta = 0.0;
  double omega_radps = 0.0;
};

/// A query point and the neighbours whose plane it is measured against (indices into a ResidualPoint table).
struct PlaneAssociation {
  int query = -1;
  std::vector<int> neighbours;
  Eigen::Vector3d normal_motor = Eigen::Vector3d::UnitZ();  ///< unit plane normal, motor frame
};

/// The point in the motor frame under the parameters (T: double or a Ceres Jet).
template <typename T>
void MotorPoint(const ResidualPoint& p, const double* t0, const T* lever, const T* tilt, const T& zero,
                const T& time_offset, T* out) {
  using std::cos, std::sin;
  const T u[3] = {T(p.u[0]), T(p.u[1]), T(p.u[2])};
  T v[3];
  ceres::AngleAxisRotatePoint(tilt, u, v);
  for (int k = 0; k < 3; ++k) v[k] += t0[k] + lever[k];
  // RotZ(theta + d), d = omega * time_offset - zero: cos = c cd - s sd, sin = s cd + c sd.
  const T d = p.omega_radps * time_offset - zero, cd = cos(d), sd = sin(d);
  const T c = p.cos_theta * cd - p.sin_theta * sd, s = p.sin_theta * cd + p.cos_theta * sd;
  out[0] = c * v[0] - s * v[1];
  out[1] = s * v[0] + c * v[1];
  out[2] = v[2];
}

/// Ceres functor of one association (parameter blocks: lever 3, tilt 3, encoder zero 1, time offset 1; one
/// residual [m]).
/// Holds pointers to the point table and the association, which must outlive it.
struct RotorPlaneCost {
  RotorPlaneCost(const std::vector<ResidualPoint>* points, const PlaneAssociation* association, const double* t0)
      : points_(points), a_(association), t0_(t0) {}

  template <typename T>
  bool operator()(const T* lever, const T* tilt, const T* zero, const T* time_offset, T* residual) const {
    T q[3], p[3], mean[3] = {T(0), T(0), T(0)};
    MotorPoint((*points_)[a_->query], t0_, lever, tilt, zero[0], time_offset[0], q);
    for (int j : a_->neighbours) {
      MotorPoint((*points_)[j], t0_, lever, tilt, zero[0], time_offset[0], p);
      for (int k = 0; k < 3; ++k) mean[k] += p[k];
    }
    const double inv = 1.0 / double(a_->neighbours.size());
    residual[0] = T(0);
    for (int k = 0; k < 3; ++k) residual[0] += a_->normal_motor[k] * (q[k] - mean[k] * inv);
    return true;
  }

 private:
  const std::vector<ResidualPoint>* points_;
  const PlaneAssociation* a_;
  const double* t0_;
};

}  // namespace rotolidar::bench
