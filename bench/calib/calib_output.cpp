#include "bench/calib/calib_output.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "bench/report/svg_raster.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/types/geometry.hpp"
#include "sim/truth/clock_truth.hpp"

namespace rotolidar::bench {
namespace {

nlohmann::json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json ComparisonJson(const CalibComparison& c) {
  return {{"lever_m", Vec(c.lever_m)}, {"tilt_deg", Vec(c.tilt_rad * 180.0 / M_PI)},
          {"encoder_zero_rad", c.encoder_zero_rad}, {"imu_time_offset_s", c.imu_time_offset_s}};
}

nlohmann::json MotionJson(const CalibrationReport& rep) {
  if (!rep.motion_ran) return {{"ran", false}, {"note", rep.motion_note}};
  const MotionCalibResult& m = rep.motion;
  return {{"ran", true},
          {"span_s", {m.t_start_s, m.t_end_s}},
          {"scans", m.scans},
          {"path_length_m", m.path_length_m},
          {"rotation_rad", m.rotation_rad},
          {"encoder_zero_change_rad", m.encoder_zero_change_rad},
          {"imu_time_offset_change_s", m.imu_time_offset_change_s},
          {"encoder_zero_spread_rad", m.encoder_zero_spread_rad},
          {"imu_time_offset_spread_s", m.imu_time_offset_spread_s},
          {"settled", m.settled},
          {"median_scan_ms", m.median_scan_ms}};
}

nlohmann::json PoseJson(const Pose3& T) {
  const Eigen::Quaterniond q(T.linear());
  return {{"translation_m", Vec(T.translation())}, {"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}}};
}

/// Per parameter: estimate (correction), sigma, independence, observable; inf sigma as null.
nlohmann::json ParametersJson(const RotorCalibResult& r) {
  nlohmann::json out = nlohmann::json::object();
  for (int p = 0; p < kCalibParamCount; ++p) {
    const ParamObservability& o = r.observability[p];
    out[CalibParamName(p)] = {{"estimated", o.estimated}, {"change", r.correction.Get(p)},
                              {"sigma", std::isfinite(o.sigma) ? nlohmann::json(o.sigma) : nlohmann::json(nullptr)},
                              {"independence", o.independence}, {"observable", o.observable}};
  }
  return out;
}

nlohmann::json IterationsJson(const RotorCalibResult& r) {
  nlohmann::json out = nlohmann::json::array();
  for (const CalibIteration& it : r.iterations)
    out.push_back({{"associations", it.associations}, {"initial_cost", it.initial_cost},
                   {"final_cost", it.final_cost}, {"median_abs_residual_m", it.median_abs_residual_m},
                   {"solver_iterations", it.solver_iterations}});
  return out;
}

}  // namespace

CalibComparison CompareCalib(const RigCalib& est, const RigCalib& ref) {
  CalibComparison c;
  c.lever_m = est.T_rotor_lidar.translation() - ref.T_rotor_lidar.translation();
  c.tilt_rad = LogSO3(est.T_rotor_lidar.linear() * ref.T_rotor_lidar.linear().transpose());
  c.encoder_zero_rad = est.encoder.zero_offset_rad - ref.encoder.zero_offset_rad;
  c.imu_time_offset_s = est.imu_time_offset_s - ref.imu_time_offset_s;
  return c;
}

Status LoadTwinTruth(const std::string& rec_dir, double t_ref_s, RigCalib* truth) {
  if (Status s = LoadCalibYaml(rec_dir + "/truth/calib_true.yaml", truth); !s) return s;
  if (!std::filesystem::exists(rec_dir + "/truth/clocks.yaml")) return Status::Ok();
  sim::ClockTruth clocks;
  if (Status s = sim::ReadClockTruth(rec_dir, &clocks); !s) return s;
  truth->encoder.zero_offset_rad -= truth->motor_speed_radps * (clocks.encoder.Stamp(t_ref_s) - t_ref_s);
  truth->imu_time_offset_s = clocks.imu.Stamp(t_ref_s) - t_ref_s;
  return Status::Ok();
}

Status WriteCalibrationJson(const std::string& path, const CalibrationReport& rep) {
  const RotorCalibResult& r = rep.result;
  nlohmann::json j;
  j["recording"] = rep.recording;
  j["static_span_s"] = {rep.span.t_start_s, rep.span.t_end_s};
  j["static_span_detected"] = rep.span_detected;
  j["points"] = rep.points;
  j["input"] = {{"T_rotor_lidar", PoseJson(rep.input.T_rotor_lidar)},
                {"encoder_zero_rad", rep.input.encoder.zero_offset_rad},
                {"lidar_clock_offset_s", rep.input.lidar_clock_offset_s},
                {"imu_time_offset_s", rep.input.imu_time_offset_s}};
  j["output"] = {{"T_rotor_lidar", PoseJson(rep.output.T_rotor_lidar)},
                 {"encoder_zero_rad", rep.output.encoder.zero_offset_rad},
                 {"lidar_clock_offset_s", rep.output.lidar_clock_offset_s},
                 {"imu_time_offset_s", rep.output.imu_time_offset_s}};
  j["change"] = ComparisonJson(CompareCalib(rep.output, rep.input));
  j["change"]["time_offset_s"] = rep.output.lidar_clock_offset_s - rep.input.lidar_clock_offset_s;
  j["parameters"] = ParametersJson(r);
  j["final_cost"] = r.iterations.empty() ? 0.0 : r.iterations.back().final_cost;
  j["initial_cost"] = r.iterations.empty() ? 0.0 : r.iterations.front().initial_cost;
  j["outer_iterations"] = r.iterations.size();
  j["solver_iterations"] = r.solver_iterations;
  j["converged"] = r.converged;
  j["residual_sigma_m"] = r.residual_sigma_m;
  j["median_abs_residual_m"] = {{"before", rep.median_abs_before_m}, {"after", rep.median_abs_after_m}};
  j["iterations"] = IterationsJson(r);
  j["motion"] = MotionJson(rep);
  std::vector<std::vector<double>> H(kCalibParamCount, std::vector<double>(kCalibParamCount));
  for (int a = 0; a < kCalibParamCount; ++a)
    for (int b = 0; b < kCalibParamCount; ++b) H[a][b] = r.hessian(a, b);
  j["hessian"] = H;
  if (rep.has_truth)
    j["truth_error"] = {{"before", ComparisonJson(rep.truth_before)}, {"after", ComparisonJson(rep.truth_after)}};
  std::ofstream f(path);
  f << j.dump(2) << "\n";
  return f ? Status::Ok() : Status::Error(path + ": cannot write");
}

Status WriteCrispnessPicture(const std::string& path, const std::string& title,
                             const std::vector<RotorPoint>& points, const RigCalib& calib,
                             const RotorCalibOptions& options,
                             const RotorCalibParams& correction, double* median_abs_m) {
  const std::vector<ResidualPoint> table = PrepareResidualPoints(points, calib);
  const Eigen::Vector3d t = calib.T_rotor_lidar.translation();
  const double t0[3] = {t.x(), t.y(), t.z()};
  std::vector<float> xyz;
  MotorFramePoints(table, t0, correction, &xyz);
  RotorCalibOptions dense = options;  // more queries than the solve: the picture averages them per cell
  dense.max_queries = 4 * options.max_queries;
  const std::vector<int> sector = RotorSectors(points, correction, options.sectors);
  const std::vector<PlaneAssociation> a = AssociatePlanes(table, xyz, sector, dense);
  const std::vector<double> r = PlaneResiduals(table, t0, a, correction);
  std::vector<Eigen::Vector2d> xy;
  std::vector<double> values, all;
  for (std::size_t i = 0; i < a.size(); ++i) {
    all.push_back(std::abs(r[i]));
    const Eigen::Vector3d p_base = calib.T_base_motor * Eigen::Vector3f(&xyz[3 * a[i].query]).cast<double>();
    if (std::abs(p_base.z()) > 0.4) continue;
    // Positive: a point of the first rotor half lies in front of (nearer the sensor than) the second half's
    // surface, or a second-half point behind the first half's; a calibration error paints walls one colour.
    const bool facing = a[i].normal_motor.dot(RayDirectionMotor(table[a[i].query])) < 0.0;
    const bool first_half = sector[a[i].query] < options.sectors / 2;
    xy.emplace_back(p_base.x(), p_base.y());
    values.push_back(facing == first_half ? r[i] : -r[i]);
  }
  std::sort(all.begin(), all.end());
  *median_abs_m = all.empty() ? 0.0 : all[all.size() / 2];
  TopViewOptions tv;
  tv.cell_m = 0.15;
  tv.colormap = Colormap::kTurbo;
  tv.value_min = -0.006, tv.value_max = 0.006;
  tv.colorbar_label = "first rotor half ahead of the second [m], cell mean";
  PlotOptions po;
  po.title = title;
  po.x_label = "base x [m]", po.y_label = "base y [m]";
  po.width_px = 760, po.height_px = 640;
  std::ofstream f(path);
  f << PointTopViewSvg(xy, values, tv, po);
  return f ? Status::Ok() : Status::Error(path + ": cannot write");
}

}  // namespace rotolidar::bench
