#include "bench/calib/rotor_residual.hpp"

#include "core/types/geometry.hpp"

namespace rotolidar::bench {

const char* CalibParamName(int param) {
  static const char* const kNames[kCalibParamCount] = {"lever_x_m", "lever_y_m", "lever_z_m", "tilt_x_rad",
                                                       "tilt_y_rad", "tilt_z_rad", "encoder_zero_rad",
                                                       "time_offset_s"};
  return param >= 0 && param < kCalibParamCount ? kNames[param] : "unknown";
}

double RotorCalibParams::Get(int param) const {
  if (param < kTiltX) return lever_m[param];
  if (param < kEncoderZero) return tilt_rad[param - kTiltX];
  return param == kEncoderZero ? encoder_zero_rad : time_offset_s;
}

void RotorCalibParams::Set(int param, double value) {
  if (param < kTiltX) lever_m[param] = value;
  else if (param < kEncoderZero) tilt_rad[param - kTiltX] = value;
  else if (param == kEncoderZero) encoder_zero_rad = value;
  else time_offset_s = value;
}

RigCalib ApplyCorrection(const RigCalib& calib, const RotorCalibParams& d) {
  RigCalib out = calib;
  const Eigen::Vector3d tilt(d.tilt_rad[0], d.tilt_rad[1], d.tilt_rad[2]);
  out.T_rotor_lidar.linear() = ExpSO3(tilt) * calib.T_rotor_lidar.linear();
  out.T_rotor_lidar.translation() += Eigen::Vector3d(d.lever_m[0], d.lever_m[1], d.lever_m[2]);
  out.encoder.zero_offset_rad = calib.encoder.zero_offset_rad + d.encoder_zero_rad;
  out.lidar_clock_offset_s = calib.lidar_clock_offset_s + d.time_offset_s;
  return out;
}

}  // namespace rotolidar::bench
