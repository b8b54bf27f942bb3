// `rotolidar calibrate REC --out DIR`: the VLP-16's lever arm and tilt on the rotor (T_rotor_lidar) from a stretch
// where the base stands still while the rotor turns, by making the points seen from opposite rotor angles agree,
// then the encoder zero and the LiDAR-IMU time offset from the motion that follows (bench/calib/,
// docs/calibration.md). Writes the corrected calib.yaml, calibration.json and before / after pictures; with a twin
// recording's truth/calib_true.yaml also the errors against the true calibration.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "bench/calib/calib_data.hpp"
#include "bench/calib/calib_output.hpp"
#include "bench/calib/rotor_calib.hpp"
#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"

namespace rotolidar::bench {
namespace {

int CalibUsage(const std::string& message) {
  std::cerr << "error: calibrate: " << message << "\n";
  return 2;
}

/// "lever_x,lever_y,..." (CalibParamName without the unit suffix) into the estimate mask.
Status ParseEstimate(const std::string& text, std::array<bool, kCalibParamCount>* estimate) {
  estimate->fill(false);
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    bool found = false;
    for (int p = 0; p < kCalibParamCount; ++p) {
      const std::string name = CalibParamName(p);
      if (name.substr(0, name.rfind('_')) == item) (*estimate)[p] = found = true;
    }
    if (!found)
      return Status::Error("--estimate: unknown parameter '" + item + "' (lever_x, lever_y, lever_z, tilt_x, "
                           "tilt_y, tilt_z, encoder_zero, time_offset)");
  }
  return Status::Ok();
}

/// A default value as the help table shows it (shortest round-trip form: "0.4", not "0.400000").
std::string Num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void AddOptions(OptionParser* p) {
  const RotorCalibOptions c;
  const RotorPointOptions d;
  p->AddPositional("RECORDING", "recording folder (docs/recording_format.md) starting with the base still and the "
                                "rotor turning");
  p->Add("out", "runs/calibrate", "-", "output folder: calib.yaml, calibration.json, map_before.svg, map_after.svg, "
                                       "motion/ (the motion stage's SLAM run)");
  p->Add("static-span", "", "s", "A:B, the stretch of rig time where the base stands still; empty = detect it "
                                 "from the IMU (the first seconds without motion)");
  p->Add("min-range", Num(d.min_range_m), "m", "closer returns are not used");
  p->Add("max-range", Num(d.max_range_m), "m", "farther returns are not used");
  p->Add("max-points", std::to_string(d.max_points), "-", "points used at most (evenly thinned)");
  p->Add("queries", std::to_string(c.max_queries), "-", "query points (point-to-plane residuals) at most");
  p->Add("neighbours", std::to_string(c.neighbours), "-", "neighbours that define a query's plane (3..32)");
  p->Add("radius", Num(c.neighbour_radius_m), "m", "neighbours farther than this are not used");
  p->Add("sectors", std::to_string(c.sectors), "-", "rotor-angle sectors (even); queries meet the opposite one");
  p->Add("max-incidence", Num(c.max_incidence_deg), "deg",
         "queries whose ray meets their plane more obliquely than this are not used (grazing returns)");
  p->Add("huber", Num(c.huber_m), "m", "Huber loss scale of the point-to-plane residual");
  p->Add("iterations", std::to_string(c.max_outer_iterations), "-", "re-associations at most");
  p->Add("threads", std::to_string(c.threads), "-", "Ceres threads");
  p->Add("motion", "auto", "-", "auto|on|off: the motion stage (encoder zero, LiDAR-IMU time offset) over the data "
                                "after the static span; auto runs it when at least --min-motion follow");
  p->Add("min-motion", Num(MotionCalibOptions{}.min_motion_s), "s", "data after the static span the motion stage "
                                                                     "needs at least");
  p->Add("slam-config", "", "-", "estimator config YAML for the motion stage (keys of slam_config.yaml)");
  p->Add("estimate", "lever_x,lever_y,tilt_x,tilt_y", "-",
         "parameters to estimate (rotor frame): lever_x|y|z, tilt_x|y|z, encoder_zero, time_offset (the LiDAR's "
         "clock against the encoder's); a static stretch observes only the default four, time_offset also when "
         "the rotor speed changes (docs/calibration.md, Observability)");
}

Status ReadOptions(const OptionParser& p, RotorPointOptions* po, RotorCalibOptions* co, TimeSpan* span) {
  long max_points = 0, queries = 0, neighbours = 0, sectors = 0, iterations = 0, threads = 0;
  for (const Status& s : {p.GetDouble("min-range", &po->min_range_m), p.GetDouble("max-range", &po->max_range_m),
                          p.GetInt("max-points", &max_points), p.GetInt("queries", &queries),
                          p.GetInt("neighbours", &neighbours), p.GetDouble("radius", &co->neighbour_radius_m),
                          p.GetInt("sectors", &sectors), p.GetDouble("huber", &co->huber_m),
                          p.GetDouble("max-incidence", &co->max_incidence_deg),
                          p.GetInt("iterations", &iterations), p.GetInt("threads", &threads),
                          ParseEstimate(p.Get("estimate"), &co->estimate)})
    if (!s) return s;
  if (max_points < 1000 || queries < 10 || queries > 10000000)
    return Status::Error("--max-points must be >= 1000 and --queries 10..1e7");
  if (!p.Get("static-span").empty())
    if (Status s = ParseTimeSpan(p.Get("static-span"), span); !s) return Status::Error("--static-span: " + s.message);
  po->max_points = std::size_t(max_points);
  co->max_queries = int(queries), co->neighbours = int(neighbours), co->sectors = int(sectors);
  co->max_outer_iterations = int(iterations), co->threads = int(threads);
  std::string why;
  if (!po->Validate(&why) || !co->Validate(&why)) return Status::Error(why);
  return Status::Ok();
}

/// The static span: --static-span (already parsed), else detected from the IMU.
Status FindSpan(const OptionParser& p, const Recording& rec, CalibrationReport* report) {
  if (!p.Get("static-span").empty()) return Status::Ok();
  report->span_detected = true;
  const Status s = DetectStaticSpan(rec.imu, StaticSpanOptions{}, &report->span);
  return s ? s : Status::Error(rec.dir + "/imu.csv: " + s.message);
}

void PrintComparison(const char* label, const CalibComparison& c) {
  std::printf("  %s: lever [%+.2f %+.2f %+.2f] mm, tilt [%+.3f %+.3f %+.3f] deg, encoder zero %+.3f deg, IMU time "
              "offset %+.2f ms\n", label, 1e3 * c.lever_m.x(), 1e3 * c.lever_m.y(), 1e3 * c.lever_m.z(),
              c.tilt_rad.x() * 180 / M_PI, c.tilt_rad.y() * 180 / M_PI, c.tilt_rad.z() * 180 / M_PI,
              c.encoder_zero_rad * 180 / M_PI, 1e3 * c.imu_time_offset_s);
}

void PrintMotion(const CalibrationReport& rep) {
  if (!rep.motion_ran) {
    std::printf("  motion: not run (%s)\n", rep.motion_note.c_str());
    return;
  }
  const MotionCalibResult& m = rep.motion;
  std::printf("  motion: %.2f..%.2f s, %zu scans, path %.1f m, rotation %.0f deg, %.1f ms per scan; %s\n",
              m.t_start_s, m.t_end_s, m.scans, m.path_length_m, m.rotation_rad * 180 / M_PI, m.median_scan_ms,
              m.settled ? "settled" : "NOT settled (spread above the limits: a longer or livelier motion helps)");
  std::printf("  encoder_zero      change %+9.4f deg, spread %.4f deg\n", m.encoder_zero_change_rad * 180 / M_PI,
              m.encoder_zero_spread_rad * 180 / M_PI);
  std::printf("  imu_time_offset   change %+9.3f ms , spread %.3f ms\n", 1e3 * m.imu_time_offset_change_s,
              1e3 * m.imu_time_offset_spread_s);
}

void PrintResult(const CalibrationReport& rep) {
  const RotorCalibResult& r = rep.result;
  std::printf("rotolidar calibrate: %s, static %.2f..%.2f s (%s), %zu points\n", rep.recording.c_str(),
              rep.span.t_start_s, rep.span.t_end_s, rep.span_detected ? "from the IMU" : "given", rep.points);
  std::printf("  solve : %zu outer iterations, %d solver iterations, %s, %d planes, cost %.4g -> %.4g\n",
              r.iterations.size(), r.solver_iterations, r.converged ? "converged" : "NOT converged",
              r.iterations.empty() ? 0 : r.iterations.back().associations,
              r.iterations.empty() ? 0.0 : r.iterations.front().initial_cost,
              r.iterations.empty() ? 0.0 : r.iterations.back().final_cost);
  std::printf("  map   : median |point-to-plane| %.4f m before, %.4f m after; residual sigma %.4f m\n",
              rep.median_abs_before_m, rep.median_abs_after_m, r.residual_sigma_m);
  for (int p = 0; p < kCalibParamCount; ++p) {
    const ParamObservability& o = r.observability[p];
    const bool deg = p >= kTiltX && p != kTimeOffset;
    const double scale = deg ? 180.0 / M_PI : 1e3;
    const char* unit = deg ? "deg" : p == kTimeOffset ? "ms " : "mm ";
    std::printf("  %-17s %s change %+9.4f %s, sigma %9.3g %s, independence %.2e%s\n", CalibParamName(p),
                o.estimated ? "estimated" : "held     ", scale * r.correction.Get(p), unit, scale * o.sigma, unit,
                o.independence, o.observable ? "" : " (unobservable here)");
  }
  PrintMotion(rep);
  if (!rep.has_truth) return;
  std::printf("  truth (truth/calib_true.yaml, clocks.yaml), estimate - true:\n");
  PrintComparison("before", rep.truth_before);
  PrintComparison("after ", rep.truth_after);
}

/// --motion, --min-motion and --slam-config, read before any work so that a typo fails at once.
struct MotionStage {
  std::string mode;  ///< auto, on or off
  MotionCalibOptions options;
};

Status ReadMotionOptions(const OptionParser& p, MotionStage* m) {
  m->mode = p.Get("motion");
  if (m->mode != "auto" && m->mode != "on" && m->mode != "off") return Status::Error("--motion: auto, on or off");
  if (Status s = p.GetDouble("min-motion", &m->options.min_motion_s); !s) return s;
  if (Status s = LoadSlamConfig(p.Get("slam-config"), &m->options.estimator); !s) return s;
  std::string why;
  return m->options.Validate(&why) ? Status::Ok() : Status::Error(why);
}

/// The motion stage after the static one, into <out>/motion: rep->output gains its corrections.
Status RunMotionStage(const MotionStage& m, const std::string& out, const Recording& rec, CalibrationReport* rep) {
  if (m.mode == "off") return rep->motion_note = "--motion off", Status::Ok();
  const double data_end_s = rec.imu.empty() ? 0.0 : rec.imu.back().t_s;
  if (data_end_s - rep->span.t_end_s < m.options.min_motion_s) {
    std::ostringstream os;
    os << "only " << std::max(0.0, data_end_s - rep->span.t_end_s) << " s of IMU data after the static span; "
       << "--min-motion is " << m.options.min_motion_s << " s";
    if (m.mode == "on") return Status::Error(rec.dir + ": --motion on: " + os.str());
    return rep->motion_note = os.str(), Status::Ok();
  }
  if (Status s = CalibrateMotion(rec.dir, rep->output, rep->span.t_end_s, m.options, out + "/motion", &rep->motion);
      !s)
    return s;
  rep->motion_ran = true;
  rep->output = ApplyMotionCorrection(rep->output, rep->motion);
  return Status::Ok();
}

/// Writes the outputs of a finished calibration into `out`.
Status WriteOutputs(const std::string& out, const std::vector<RotorPoint>& points, CalibrationReport* rep) {
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) return Status::Error(out + ": cannot create: " + ec.message());
  if (Status s = SaveCalibYaml(out + "/calib.yaml", rep->output); !s) return s;
  if (Status s = WriteCrispnessPicture(out + "/map_before.svg", "static map, input calibration", points, rep->input,
                                       rep->options, RotorCalibParams{}, &rep->median_abs_before_m);
      !s)
    return s;
  if (Status s = WriteCrispnessPicture(out + "/map_after.svg", "static map, estimated calibration", points,
                                       rep->input, rep->options, rep->result.correction, &rep->median_abs_after_m);
      !s)
    return s;
  return WriteCalibrationJson(out + "/calibration.json", *rep);
}

}  // namespace

int CmdCalibrate(int argc, char** argv) {
  OptionParser p("calibrate", "Estimate the VLP-16's lever arm and tilt on the rotor (T_rotor_lidar) from a stretch "
                              "where the base stands still while the rotor turns, then the encoder zero and the "
                              "LiDAR-IMU time offset from the motion after it; writes a corrected calib.yaml, "
                              "calibration.json and before/after pictures (docs/calibration.md).");
  AddOptions(&p);
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  CalibrationReport rep;
  RotorPointOptions point_options;
  MotionStage motion;
  if (Status s = ReadOptions(p, &point_options, &rep.options, &rep.span); !s) return CalibUsage(s.message);
  if (Status s = ReadMotionOptions(p, &motion); !s) return CalibUsage(s.message);
  Recording rec;
  if (Status s = LoadRecording(p.Get("RECORDING"), &rec); !s) return Fail(s);
  rep.recording = rec.dir;
  rep.input = rec.calib;
  if (Status s = FindSpan(p, rec, &rep); !s) return Fail(s);
  std::vector<RotorPoint> points;
  if (Status s = LoadRotorPoints(rec, rec.calib, rep.span, point_options, &points); !s) return Fail(s);
  rec.lidar_packets.clear();
  rec.lidar_packets.shrink_to_fit();
  rep.points = points.size();
  if (Status s = CalibrateRotor(points, rec.calib, rep.options, &rep.result); !s) return Fail(s);
  rep.output = ApplyCorrection(rec.calib, rep.result.correction);
  if (Status s = RunMotionStage(motion, p.Get("out"), rec, &rep); !s) return Fail(s);
  RigCalib truth;
  if (std::filesystem::exists(rec.dir + "/truth/calib_true.yaml")) {
    if (Status s = LoadTwinTruth(rec.dir, rep.motion_ran ? rep.motion.t_end_s : rep.span.t_end_s, &truth); !s)
      return Fail(s);
    rep.has_truth = true;
    rep.truth_before = CompareCalib(rep.input, truth);
    rep.truth_after = CompareCalib(rep.output, truth);
  }
  if (Status s = WriteOutputs(p.Get("out"), points, &rep); !s) return Fail(s);
  PrintResult(rep);
  std::printf("  output: %s (calib.yaml, calibration.json, map_before.svg, map_after.svg%s)\n", p.Get("out").c_str(),
              rep.motion_ran ? ", motion/" : "");
  return 0;
}

}  // namespace rotolidar::bench
