#pragma once
// What `rotolidar calibrate` writes (docs/calibration.md): calibration.json, the corrected calib.yaml and the
// before / after pictures of the static map, plus the comparison with a twin recording's true calibration.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bench/calib/calib_data.hpp"
#include "bench/calib/motion_calib.hpp"
#include "bench/calib/rotor_calib.hpp"
#include "core/types/calib.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

/// A calibration against a reference (the twin's truth/calib_true.yaml): est - ref per component.
struct CalibComparison {
  Eigen::Vector3d lever_m = Eigen::Vector3d::Zero();   ///< translation difference, rotor frame [m]
  Eigen::Vector3d tilt_rad = Eigen::Vector3d::Zero();  ///< LogSO3(R_est * R_ref^T), rotor frame [rad]
  double encoder_zero_rad = 0.0;                       ///< zero offset difference [rad]
  double imu_time_offset_s = 0.0;                      ///< imu_time_offset_s difference [s]
};
CalibComparison CompareCalib(const RigCalib& estimate, const RigCalib& reference);

/// A twin recording's true calibration as the map sees it at rig time t_ref_s: truth/calib_true.yaml, with the
/// encoder zero less the rotor speed times the encoder clock's offset (a late encoder stamp turns every angle back
/// by the speed times the lag, as a zero would) and imu_time_offset_s the IMU clock's offset, both from
/// truth/clocks.yaml when the recording has it. Fails naming the file.
Status LoadTwinTruth(const std::string& recording_dir, double t_ref_s, RigCalib* truth);

/// Everything calibration.json records about one run.
struct CalibrationReport {
  std::string recording;
  TimeSpan span;
  bool span_detected = false;      ///< from the IMU (else given)
  std::size_t points = 0;          ///< points used (after thinning)
  RigCalib input, output;
  RotorCalibOptions options;
  RotorCalibResult result;
  double median_abs_before_m = 0.0, median_abs_after_m = 0.0;  ///< |point-to-plane| of each picture's queries
  bool motion_ran = false;         ///< the motion stage ran (motion_calib.hpp); else motion_note says why not
  std::string motion_note;
  MotionCalibResult motion;
  bool has_truth = false;
  CalibComparison truth_before, truth_after;  ///< input - truth, output - truth
};

/// calibration.json: the estimates, their change from the input, cost, iterations, convergence, and per
/// parameter the observability (ParamObservability). Fails naming the file.
Status WriteCalibrationJson(const std::string& path, const CalibrationReport& report);

/// The static map under `correction`: a top view (base frame, 0.15 m cells: means of tens of points) of query
/// points (4x the solve's) within +-0.4 m of the base origin's height, coloured by the cell mean of the signed
/// distance between the two rotor halves' views of the surface (+-6 mm scale; 0 = crisp, a calibration error
/// paints walls one colour).
/// *median_abs_m: the median |point-to-plane| over all those queries. Fails naming the file.
Status WriteCrispnessPicture(const std::string& path, const std::string& title,
                             const std::vector<RotorPoint>& points, const RigCalib& calib,
                             const RotorCalibOptions& options, const RotorCalibParams& correction,
                             double* median_abs_m);

}  // namespace rotolidar::bench
