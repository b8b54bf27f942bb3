#include "bench/calib/motion_calib.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include "bench/eval/statistics.hpp"
#include "bench/run/slam_run.hpp"
#include "core/types/geometry.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::bench {
namespace {

/// The scans after motion_start_s in which the window ran.
std::vector<const ScanReport*> MovingScans(const std::vector<ScanReport>& scans, double motion_start_s) {
  std::vector<const ScanReport*> out;
  for (const ScanReport& s : scans)
    if (s.t_start_s >= motion_start_s && s.imu_initialized) out.push_back(&s);
  return out;
}

/// Estimates at the last scan, their spread over the second half, and the motion they saw.
void Summarise(const std::vector<const ScanReport*>& moving, MotionCalibResult* r) {
  r->scans = moving.size();
  r->t_start_s = moving.front()->t_start_s, r->t_end_s = moving.back()->t_end_s;
  r->encoder_zero_change_rad = moving.back()->rotor_offset_rad;
  r->imu_time_offset_change_s = moving.back()->imu_time_offset_s;
  std::vector<double> phi, td;
  for (std::size_t i = moving.size() / 2; i < moving.size(); ++i)
    phi.push_back(moving[i]->rotor_offset_rad), td.push_back(moving[i]->imu_time_offset_s);
  r->encoder_zero_spread_rad = ComputeStatistics(phi).std, r->imu_time_offset_spread_s = ComputeStatistics(td).std;
  for (std::size_t i = 1; i < moving.size(); ++i) {
    const Pose3 d = moving[i - 1]->T_world_base.inverse() * moving[i]->T_world_base;
    r->path_length_m += d.translation().norm();
    r->rotation_rad += LogSO3(d.linear()).norm();
  }
}

}  // namespace

bool MotionCalibOptions::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) { return FailValidation(error, "motion calibration: " + m); };
  if (!(min_motion_s > 0.0)) return fail("min_motion_s must be > 0");
  if (!(max_spread_rad > 0.0) || !(max_spread_s > 0.0)) return fail("the spread limits must be > 0");
  if (!estimator.use_imu) return fail("the estimator must use the IMU (use_imu: true)");
  return estimator.Validate(error);
}

Status CalibrateMotion(const std::string& recording_dir, const RigCalib& calib, double motion_start_s,
                       const MotionCalibOptions& options, const std::string& out_dir, MotionCalibResult* result) {
  std::string why;
  if (!options.Validate(&why)) return Status::Error(why);
  EstimatorConfig config = options.estimator;
  config.window.estimate_rotor_offset = true;
  config.window.estimate_time_offset = true;
  SlamRunOptions run_options;
  run_options.calib = &calib;
  SlamRunResult run;
  if (Status s = RunSlam(recording_dir, config, out_dir, &run, run_options); !s)
    return Status::Error("motion calibration: " + s.message);
  const std::vector<const ScanReport*> moving = MovingScans(run.scans, motion_start_s);
  const double span = moving.empty() ? 0.0 : moving.back()->t_end_s - moving.front()->t_start_s;
  if (span < options.min_motion_s) {
    std::ostringstream os;
    os << recording_dir << ": motion calibration needs " << options.min_motion_s << " s of data after the static "
       << "span (ending at " << motion_start_s << " s) with the IMU window running; it has " << span << " s";
    return Status::Error(os.str());
  }
  *result = MotionCalibResult{};
  Summarise(moving, result);
  result->median_scan_ms = run.median_scan_ms;
  result->settled = result->encoder_zero_spread_rad <= options.max_spread_rad &&
                    result->imu_time_offset_spread_s <= options.max_spread_s;
  return Status::Ok();
}

RigCalib ApplyMotionCorrection(const RigCalib& calib, const MotionCalibResult& result) {
  RigCalib out = calib;
  out.encoder.zero_offset_rad += result.encoder_zero_change_rad;
  out.imu_time_offset_s += result.imu_time_offset_change_s;
  return out;
}

}  // namespace rotolidar::bench
