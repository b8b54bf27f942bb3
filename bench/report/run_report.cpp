#include "bench/report/run_report.hpp"


#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bench/eval/trajectory_lookup.hpp"
#include "bench/loops/loop_report.hpp"
#include "bench/report/html_report.hpp"
#include "bench/run/atomic_write.hpp"
#include "bench/report/visual_section.hpp"
#include "bench/report/run_report_sections.hpp"
#include "bench/run/scan_health.hpp"
#include "core/util/log.hpp"

namespace rotolidar::bench {
namespace {

using Rows = std::vector<std::pair<std::string, std::string>>;

double RealtimeFactor(const SlamRunResult& s) { return s.wall_time_s > 0 ? s.data_duration_s / s.wall_time_s : 0.0; }

void AddSlamRows(const SlamRunResult& s, Rows* rows) {
  size_t attempted = 0, converged = 0, imu = 0;
  for (const ScanReport& r : s.scans) {
    attempted += r.registration.attempted;
    converged += r.registration.converged;
    imu += r.imu_initialized;
  }
  rows->push_back({"scans", std::to_string(s.scans.size())});
  rows->push_back({"data duration", Fmt("%.2f s", s.data_duration_s)});
  rows->push_back({"SLAM wall time", Fmt("%.2f s", s.wall_time_s)});
  rows->push_back({"real-time factor (data / wall)", Fmt("%.2f x", RealtimeFactor(s))});
  rows->push_back({"median time per scan", Fmt("%.1f ms", s.median_scan_ms)});
  rows->push_back({"registrations converged", std::to_string(converged) + " of " + std::to_string(attempted)});
  rows->push_back({"scans with the IMU window", std::to_string(imu)});
  rows->push_back({"map points", std::to_string(s.map_points)});
  if (s.bad_packets > 0) rows->push_back({"malformed packets", std::to_string(s.bad_packets)});
  for (const InputWarning& w : s.input_warnings) rows->push_back({"input warning: " + w.code, w.message});
  const PacketOrderCounts& o = s.packet_order;
  if (o.total() > 0)
    rows->push_back({"packets out of order (repaired / dropped)",
                     std::to_string(o.reordered) + " reordered; dropped: " + std::to_string(o.duplicate) +
                         " duplicate, " + std::to_string(o.late) + " late, " + std::to_string(o.wild) +
                         " wild timestamp"});
}

void AddTruthRows(const RunEvaluation& ev, Rows* rows) {
  const ErrorStatistics& a = ev.ape.stats;
  rows->push_back({"ATE RMSE (SE(3) aligned)", Fmt("%.4f m", a.rmse)});
  rows->push_back({"ATE mean / median / max",
                   Fmt("%.4f", a.mean) + " / " + Fmt("%.4f", a.median) + " / " + Fmt("%.4f m", a.max)});
  rows->push_back({"poses compared", std::to_string(ev.ape.num_associated)});
  if (ev.rpe.status.ok && ev.rpe.stats.count > 0)
    rows->push_back({"RPE RMSE / max over " + ev.rpe_delta,
                     Fmt("%.4f", ev.rpe.stats.rmse) + " / " + Fmt("%.4f m", ev.rpe.stats.max)});
  if (ev.has_deskew) {
    const ErrorStats& d = ev.deskew.all;
    std::string over = std::to_string(d.count) + " points";
    if (ev.deskew_scan_stride > 1) over += ", 1 scan in " + std::to_string(ev.deskew_scan_stride);
    rows->push_back({"deskew error median / p90 per point",
                     Fmt("%.4f", d.median_m) + " / " + Fmt("%.4f m", d.p90_m) + " (" + over + ")"});
  }
  if (!ev.has_map_metrics) return;
  const MapMetrics& m = ev.map;
  rows->push_back({"map-to-truth median / RMSE / p95", Fmt("%.4f", m.map_to_truth.median_m) + " / " +
                                                           Fmt("%.4f", m.map_to_truth.rmse_m) + " / " +
                                                           Fmt("%.4f m", m.map_to_truth.p95_m)});
  rows->push_back({"surface coverage", Fmt("%.1f %%", 100 * m.coverage.total.coverage)});
  if (m.coverage.has_visibility)
    rows->push_back({"completeness (visible surfaces)", Fmt("%.1f %%", 100 * m.coverage.total.completeness)});
  if (m.element_summary.elements > 0)
    rows->push_back({"element size RMSE", Fmt("%.3f m", m.element_summary.rmse_m) + " (over " +
                                              std::to_string(m.element_summary.widths_measured +
                                                             m.element_summary.heights_measured) +
                                              " measured dimensions)"});
}

void AddConfigSection(const RunReportInput& in, HtmlReport* html) {
  if (in.config_files.empty()) return;
  html->BeginSection("config", "Resolved configuration");
  for (const auto& [title, path] : in.config_files) {
    std::ifstream file(path);
    if (!file) {
      html->Note(title + ": " + path + " could not be read");
      continue;
    }
    std::stringstream text;
    text << file.rdbuf();
    html->Preformatted(title + " (" + path + ")", text.str());
  }
}

// Loop closure: the loop edges on a top view, each judged by the truth positions of its two keyframes (within
// kTrueRevisitM: a revisit; `rotolidar bench loops` judges by view overlap as well).
void AddLoopSection(const RunReportInput& in, HtmlReport* html) {
  const graph::LoopClosureState& state = in.slam->loops;
  if (state.keyframes.empty()) return;
  constexpr double kTrueRevisitM = 10.0;
  html->BeginSection("loops", "Loop closure");
  LoopVerdicts verdicts;
  int false_loops = 0, rejected = 0;
  for (const graph::LoopRecord& l : state.loops) {
    Pose3 a, b;
    int verdict = -1;
    if (in.evaluation->has_truth && PoseAt(in.evaluation->truth, state.keyframes[l.query_id].t_s, &a) &&
        PoseAt(in.evaluation->truth, state.keyframes[l.match_id].t_s, &b))
      verdict = (a.translation() - b.translation()).norm() <= kTrueRevisitM;
    verdicts.push_back(verdict);
    false_loops += verdict == 0, rejected += l.rejected;
  }
  html->KeyValueTable({{"loop keyframes", std::to_string(state.keyframes.size())},
                       {"stage-1 candidates / verified by GICP",
                        std::to_string(state.candidates_proposed) + " / " + std::to_string(state.candidates_checked)},
                       {"loops accepted / rejected by the graph",
                        std::to_string(state.loops.size()) + " / " + std::to_string(rejected)},
                       {"false loops (truth positions > 10 m apart)",
                        in.evaluation->has_truth ? std::to_string(false_loops) : "no truth"},
                       {"GICP time, total", Fmt("%.1f s", state.verify_time_s)},
                       {"longest graph solve", Fmt("%.3f s", state.max_solve_time_s)}});
  html->Figure(LoopTopViewSvg(state, verdicts),
               "Keyframes before (odometry) and after the pose graph, in the SLAM world; each loop joins its two "
               "keyframes' corrected positions (loops.csv; every candidate in loop_candidates.csv).");
}

}  // namespace

std::string RenderRunReport(const RunReportInput& in) {
  ROTOLIDAR_CHECK(in.slam != nullptr && in.evaluation != nullptr, "RenderRunReport: slam and evaluation must be set");
  const RunEvaluation& ev = *in.evaluation;
  HtmlReport html(in.title);
  html.BeginSection("headline", "Headline");
  Rows rows = in.run_info;
  AddSlamRows(*in.slam, &rows);
  if (ev.has_truth) AddTruthRows(ev, &rows);
  html.KeyValueTable(rows);
  if (!ev.has_truth)
    html.Note("Left out: APE, RPE, map accuracy, coverage and element sections (" + ev.truth_note + ").");
  else if (!ev.has_map_metrics)
    html.Note("Left out: map accuracy, coverage and element sections (" + ev.map_note + ").");
  report::AddTrajectorySection(in, &html);
  report::AddApeSection(in, &html);
  report::AddRpeSection(in, &html);
  report::AddHealthSection(in, &html);
  report::AddTimingSection(in, &html);
  report::AddMapSection(in, &html);
  report::AddCoverageSection(in, &html);
  report::AddElementsSection(in, &html);
  AddLoopSection(in, &html);
  report::AddVisualSection(in, &html);
  AddConfigSection(in, &html);
  return html.Render();
}

Status WriteRunReport(const std::string& path, const RunReportInput& input) {
  std::ofstream file(path, std::ios::binary);
  file << RenderRunReport(input);
  return file ? Status::Ok() : Status::Error(path + ": cannot write the report");
}

void AddRunMetricsJson(const SlamRunResult& s, const RunEvaluation& ev, nlohmann::json* out) {
  nlohmann::json& j = *out;
  j["slam"] = {{"scans", s.scans.size()},          {"median_scan_ms", s.median_scan_ms},
               {"wall_time_s", s.wall_time_s},     {"data_duration_s", s.data_duration_s},
               {"realtime_factor", RealtimeFactor(s)}, {"map_points", s.map_points},
               {"bad_packets", s.bad_packets}};
  j["input_warnings"] = nlohmann::json::array();
  for (const InputWarning& w : s.input_warnings)
    j["input_warnings"].push_back({{"code", w.code}, {"count", w.count}, {"message", w.message}});
  j["slam"]["packet_order"] = {{"reordered", s.packet_order.reordered}, {"duplicate", s.packet_order.duplicate},
                               {"late", s.packet_order.late}, {"wild", s.packet_order.wild}};
  for (const report::StageTiming& t : report::ComputeStageTimings(s.scans))
    j["slam"]["stage_mean_ms"][t.stage] = t.mean_ms;
  j["health"] = ScanHealthJson(AssessScanHealth(s.scans));
  // The window's online calibration at the last scan: corrections of calib.yaml's encoder zero and
  // imu_time_offset_s (0 unless window.estimate_rotor_offset / estimate_time_offset; scans.csv has them per scan).
  if (!s.scans.empty())
    j["online_calibration"] = {{"rotor_offset_rad", s.scans.back().rotor_offset_rad},
                               {"imu_time_offset_s", s.scans.back().imu_time_offset_s}};
  if (!ev.has_truth) return;
  const ErrorStatistics& a = ev.ape.stats;
  j["ape_translation_m"] = {{"alignment", "se3"}, {"poses", ev.ape.num_associated}, {"rmse", a.rmse},
                            {"mean", a.mean},     {"median", a.median},              {"std", a.std},
                            {"min", a.min},       {"max", a.max}};
  if (ev.rpe.status.ok && ev.rpe.stats.count > 0) {
    const ErrorStatistics& r = ev.rpe.stats;
    j["rpe_translation_m"] = {{"delta", ev.rpe_delta}, {"all_pairs", true}, {"pairs", r.count}, {"rmse", r.rmse},
                              {"mean", r.mean},        {"median", r.median}, {"std", r.std},    {"max", r.max}};
  }
  if (ev.has_deskew) {  // the names of ape_translation_m's statistics; the study reads deskew_error_m.median
    const ErrorStats& d = ev.deskew.all;
    j["deskew_error_m"] = {{"points", d.count},
                           {"scans", ev.deskew.per_scan.size()},
                           {"scan_stride", ev.deskew_scan_stride},
                           {"median", d.median_m},
                           {"p90", d.p90_m},
                           {"p95", d.p95_m},
                           {"rmse", d.rmse_m},
                           {"mean", d.mean_m},
                           {"max", d.max_m},
                           {"not_deskewed", ev.deskew.num_not_deskewed},
                           {"outside_truth", ev.deskew.num_outside_truth}};
  }
  if (ev.has_map_metrics) {
    nlohmann::json map;
    ToJson(ev.map, &map);
    map["scene"] = ev.scene_name;
    map["alignment"] = "se3 (the APE's)";
    j["map"] = map;
  }
  if (ev.has_dynamic) {
    nlohmann::json dynamic;
    ToJson(ev.dynamic, ev.dynamic_config, &dynamic);
    j["dynamic"] = dynamic;
  }
}

Status WriteSlamRunReport(const std::string& recording_dir, const std::string& slam_dir, const SlamRunResult& slam,
                          const RunEvaluationOptions& options, RunEvaluation* evaluation) {
  RunEvaluation local;
  RunEvaluation* ev = evaluation ? evaluation : &local;
  if (Status s = EvaluateRun(recording_dir, slam_dir, slam, "", options, ev); !s) return s;
  RunReportInput in;
  in.title = "rotolidar slam: " + recording_dir;
  in.run_info = {{"recording", recording_dir}, {"outputs", slam_dir}};
  if (slam.stopped)
    in.run_info.push_back({"stopped early", "yes: the outputs cover the first " +
                                                std::to_string(slam.data_fed_s) + " s of LiDAR data"});
  in.slam = &slam;
  in.evaluation = ev;
  in.recording_dir = recording_dir;
  in.config_files = {{"estimator (slam_config.yaml)", slam_dir + "/slam_config.yaml"},
                     {"rig calibration (calib.yaml)", recording_dir + "/calib.yaml"}};
  if (Status s = WriteAtomically(slam_dir + "/report.html",
                                 [&](const std::string& part) { return WriteRunReport(part, in); });
      !s)
    return s;
  // metrics.json last: it marks a finished run; "complete" says whether the run saw all of its data.
  nlohmann::json j;
  j["recording"] = recording_dir;
  j["complete"] = !slam.stopped;
  if (slam.stopped) j["data_fed_s"] = slam.data_fed_s;
  AddRunMetricsJson(slam, *ev, &j);
  return WriteAtomically(slam_dir + "/metrics.json", [&](const std::string& part) {
    std::ofstream file(part);
    file << j.dump(2) << "\n";
    file.close();
    return file ? Status::Ok() : Status::Error(part + ": write failed");
  });
}

}  // namespace rotolidar::bench
