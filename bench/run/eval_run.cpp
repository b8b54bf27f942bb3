#include "bench/run/eval_run.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <nlohmann/json.hpp>

namespace rotolidar::bench {
namespace {

std::string AlignmentTitle(Alignment align) {
  switch (align) {
    case Alignment::kNone: return "(not aligned)";
    case Alignment::kSe3: return "(with SE(3) Umeyama alignment)";
    case Alignment::kSim3: return "(with Sim(3) Umeyama alignment)";
    case Alignment::kPosYaw: return "(with position + yaw alignment)";
  }
  return "";
}

/// The unit of the errors: the relation's, or per segment length for the kitti metric.
std::string ErrorUnit(const EvalOptions& o) {
  if (o.metric == EvalMetric::kKitti)
    return o.pose_relation == PoseRelation::kTranslation ? "%" : "deg/100m";
  return PoseRelationUnit(o.pose_relation);
}

/// "APE", "RPE" or "KITTI": the metric's name in titles and labels.
std::string MetricLabel(EvalMetric metric) {
  switch (metric) {
    case EvalMetric::kApe: return "APE";
    case EvalMetric::kRpe: return "RPE";
    case EvalMetric::kKitti: return "KITTI segment error";
  }
  return "";
}

std::string MakeTitle(const EvalOptions& o) {
  const std::string unit = ErrorUnit(o);
  std::string title = MetricLabel(o.metric) + " w.r.t. " + PoseRelationName(o.pose_relation) +
                      (unit.empty() ? "" : " (" + unit + ")");
  if (o.metric == EvalMetric::kKitti) title += "\nover 100, 200, ..., 800 m segments from every 10th pose (devkit)";
  if (o.metric == EvalMetric::kRpe) {
    std::ostringstream d;
    d << o.delta;
    title += "\nfor delta = " + d.str() + " (" + DeltaUnitName(o.delta_unit) + ")" +
             (o.all_pairs ? " using all pairs" : " using consecutive pairs");
  }
  return title + "\n" + AlignmentTitle(o.align);
}

EvalResult Failed(EvalResult r, Status s) {
  r.status = std::move(s);
  return r;
}

nlohmann::json StatsJson(const ErrorStatistics& s) {
  return {{"max", s.max}, {"mean", s.mean}, {"median", s.median}, {"min", s.min},
          {"rmse", s.rmse}, {"sse", s.sse},  {"std", s.std}};
}

}  // namespace

bool ParseEvalMetric(const std::string& name, EvalMetric* out) {
  if (name == "ape") *out = EvalMetric::kApe;
  else if (name == "rpe") *out = EvalMetric::kRpe;
  else if (name == "kitti") *out = EvalMetric::kKitti;
  else return false;
  return true;
}

const char* EvalMetricName(EvalMetric metric) {
  switch (metric) {
    case EvalMetric::kApe: return "ape";
    case EvalMetric::kRpe: return "rpe";
    case EvalMetric::kKitti: return "kitti";
  }
  return "?";
}

bool EvalOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& msg) {
    if (error) *error = "eval options: " + msg;
    return false;
  };
  if (ref_path.empty()) return fail("ref_path is empty");
  if (est_path.empty()) return fail("est_path is empty");
  if (!(std::isfinite(max_diff_s) && max_diff_s >= 0.0)) return fail("max_diff_s must be finite and >= 0");
  if (metric == EvalMetric::kRpe) {
    if (!(std::isfinite(delta) && delta > 0.0)) return fail("delta must be finite and > 0");
    if (delta_unit == DeltaUnit::kFrames && delta != std::floor(delta)) {
      return fail("delta must be an integer when delta_unit is frames");
    }
  }
  if (metric == EvalMetric::kKitti && pose_relation != PoseRelation::kTranslation &&
      pose_relation != PoseRelation::kRotationAngleDeg)
    return fail("the kitti metric measures trans_part [%] or angle_deg [deg/100m]");
  return true;
}

EvalResult EvaluateTrajectories(const Trajectory& ref, const Trajectory& est, const EvalOptions& options,
                                bool associate) {
  EvalResult r;
  r.title = MakeTitle(options);
  r.unit = ErrorUnit(options);
  r.num_ref_poses = ref.size();
  r.num_est_poses = est.size();
  Trajectory ref_a = ref, est_a = est;
  if (associate) {
    if (Status s = AssociateTrajectories(ref, est, options.max_diff_s, &ref_a, &est_a); !s) return Failed(r, s);
  } else if (ref.size() != est.size()) {
    return Failed(r, Status::Error("reference has " + std::to_string(ref.size()) + " poses but estimate has " +
                                   std::to_string(est.size()) + " (no time association for this format)"));
  }
  r.num_associated = ref_a.size();
  r.alignment = AlignPositions(Positions(est_a), Positions(ref_a), options.align);
  if (!r.alignment.success) return Failed(r, Status::Error("alignment: " + r.alignment.message));
  est_a = ApplyAlignment(r.alignment, est_a);
  Status s;
  if (options.metric == EvalMetric::kApe) {
    s = ComputeApeErrors(ref_a, est_a, options.pose_relation, &r.errors);
  } else if (options.metric == EvalMetric::kKitti) {
    s = ComputeKittiOdometryErrors(ref_a, est_a, KittiOdometryOptions(), &r.kitti);
    const bool translation = options.pose_relation == PoseRelation::kTranslation;
    for (const KittiSegmentError& e : r.kitti.segments)
      r.errors.push_back(translation ? 100.0 * e.t_err_per_m : e.r_err_rad_per_m * kDegPer100mPerRadPerM);
  } else {
    RpeOptions rpe;
    rpe.relation = options.pose_relation;
    rpe.delta = options.delta;
    rpe.delta_unit = options.delta_unit;
    rpe.all_pairs = options.all_pairs;
    s = ComputeRpeErrors(ref_a, est_a, rpe, &r.errors);
  }
  if (!s) return Failed(r, s);
  r.stats = ComputeStatistics(r.errors);
  r.status = Status::Ok();
  return r;
}

Status RunEval(const EvalOptions& options, EvalResult* out) {
  std::string error;
  if (!options.Validate(&error)) return (out->status = Status::Error(error));
  const TrajectoryFormat est_format =
      options.format == TrajectoryFormat::kEuroc ? TrajectoryFormat::kTum : options.format;
  Trajectory ref, est;
  if (Status s = ReadTrajectory(options.ref_path, options.format, &ref); !s) return (out->status = s);
  if (Status s = ReadTrajectory(options.est_path, est_format, &est); !s) return (out->status = s);
  *out = EvaluateTrajectories(ref, est, options, options.format != TrajectoryFormat::kKitti);
  if (out->status && !options.json_path.empty()) {
    if (Status s = WriteEvalJson(options.json_path, options, *out); !s) return (out->status = s);
  }
  return out->status;
}

EvalResult ComputeApe(const Trajectory& ref, const Trajectory& est, Alignment align) {
  EvalOptions o;
  o.align = align;
  return EvaluateTrajectories(ref, est, o, true);
}

void PrintEvalStats(const EvalResult& result, std::ostream& os) {
  os << result.title << "\n\n";
  const ErrorStatistics& s = result.stats;
  const std::pair<const char*, double> rows[] = {{"max", s.max},   {"mean", s.mean}, {"median", s.median},
                                                 {"min", s.min},   {"rmse", s.rmse}, {"sse", s.sse},
                                                 {"std", s.std}};
  const auto old_flags = os.flags();
  const auto old_prec = os.precision();
  os << std::fixed << std::setprecision(6);
  for (const auto& [name, value] : rows) os << std::setw(7) << name << "\t" << value << "\n";
  if (!result.kitti.segments.empty()) {
    os << "\n length [m]  segments  t_rel [%]  r_rel [deg/100m]\n";
    for (const KittiLengthError& l : result.kitti.by_length)
      os << std::setprecision(0) << std::setw(11) << l.length_m << std::setw(10) << l.segments << std::setprecision(4)
         << std::setw(11) << l.t_rel_percent << std::setw(18) << l.r_rel_deg_per_100m << "\n";
    os << std::setprecision(4) << "KITTI devkit: t_rel " << result.kitti.t_rel_percent << " %, r_rel "
       << result.kitti.r_rel_deg_per_100m << " deg/100m over " << result.kitti.segments.size() << " segments\n";
  }
  os.flags(old_flags);
  os.precision(old_prec);
}

Status WriteEvalJson(const std::string& path, const EvalOptions& options, const EvalResult& result) {
  nlohmann::json j;
  j["title"] = result.title;
  j["ref_name"] = options.ref_path;
  j["est_name"] = options.est_path;
  j["label"] = MetricLabel(options.metric) + " (" + result.unit + ")";
  j["options"] = {{"format", TrajectoryFormatName(options.format)},
                  {"align", AlignmentName(options.align)},
                  {"metric", EvalMetricName(options.metric)},
                  {"pose_relation", PoseRelationName(options.pose_relation)},
                  {"delta", options.delta},
                  {"delta_unit", DeltaUnitName(options.delta_unit)},
                  {"all_pairs", options.all_pairs},
                  {"max_diff_s", options.max_diff_s}};
  j["num_ref_poses"] = result.num_ref_poses;
  j["num_est_poses"] = result.num_est_poses;
  j["num_associated"] = result.num_associated;
  const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> T = result.alignment.T_ref_est.matrix();
  j["alignment"] = {{"scale", result.alignment.scale},
                    {"T_ref_est_row_major", std::vector<double>(T.data(), T.data() + 16)}};
  j["stats"] = StatsJson(result.stats);
  if (options.metric == EvalMetric::kKitti)
    j["kitti"] = {{"t_rel_percent", result.kitti.t_rel_percent},
                  {"r_rel_deg_per_100m", result.kitti.r_rel_deg_per_100m},
                  {"segments", result.kitti.segments.size()}};
  std::ofstream os(path);
  if (!os) return Status::Error(path + ": cannot open for writing");
  os << j.dump(2) << "\n";
  if (!os) return Status::Error(path + ": write failed");
  return Status::Ok();
}

}  // namespace rotolidar::bench
