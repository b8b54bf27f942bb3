#include "bench/loops/loop_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <utility>

#include "bench/report/html_report.hpp"
#include "bench/report/svg_plot.hpp"

namespace rotolidar::bench {
namespace {

PlotSeries Segment(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const std::string& color, bool dashed) {
  PlotSeries s;
  s.x = {a.x(), b.x()}, s.y = {a.y(), b.y()};
  s.color = color;
  s.dashed = dashed;
  s.line_width_px = 1.2;
  return s;
}

PlotSeries CurveSeries(const std::vector<PrPoint>& curve, const std::string& label, const std::string& color) {
  PlotSeries s;
  s.label = label;
  s.color = color;
  s.markers = curve.size() < 40;
  for (const PrPoint& p : curve) s.x.push_back(p.recall), s.y.push_back(p.precision);
  return s;
}

std::string Num(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.9g", v);
  return b;
}

}  // namespace

std::string LoopTopViewSvg(const graph::LoopClosureState& state, const LoopVerdicts& verdicts) {
  PlotSeries odom, corrected;
  odom.label = "odometry", odom.color = "#999999", odom.dashed = true;
  corrected.label = "loop-closed", corrected.color = "#1f77b4";
  for (const graph::KeyframePose& k : state.keyframes) {
    odom.x.push_back(k.T_world_odom.translation().x()), odom.y.push_back(k.T_world_odom.translation().y());
    corrected.x.push_back(k.T_world_corrected.translation().x());
    corrected.y.push_back(k.T_world_corrected.translation().y());
  }
  std::vector<PlotSeries> series = {odom, corrected};
  bool labelled[3] = {false, false, false};
  const char* names[3] = {"loop", "false loop (truth)", "rejected by the graph"};
  for (size_t i = 0; i < state.loops.size(); ++i) {
    const graph::LoopRecord& l = state.loops[i];
    const int kind = l.rejected ? 2 : (i < verdicts.size() && verdicts[i] == 0 ? 1 : 0);
    const char* colors[3] = {"#2ca02c", "#d62728", "#7f7f7f"};
    series.push_back(Segment(state.keyframes[l.query_id].T_world_corrected.translation(),
                             state.keyframes[l.match_id].T_world_corrected.translation(), colors[kind], kind == 2));
    if (!labelled[kind]) series.back().label = names[kind], labelled[kind] = true;
  }
  PlotOptions o;
  o.title = "keyframes and loop edges (top view)";
  o.x_label = "x [m]", o.y_label = "y [m]";
  o.equal_aspect = true, o.legend_above = true;
  o.width_px = 620, o.height_px = 500;
  return LinePlotSvg(series, o);
}

std::string LoopPrSvg(const LoopPrResult& r) {
  std::vector<PlotSeries> series = {CurveSeries(r.stage1, "stage 1 alone (Scan Context distance)", "#ff7f0e"),
                                    CurveSeries(r.stage2, "stage 2 alone (GICP fitness, odometry neighbour)", "#9467bd"),
                                    CurveSeries(r.both, "both (GICP fitness after the descriptor gate)", "#1f77b4")};
  PlotSeries op;
  op.label = "operating point";
  op.color = "#d62728", op.line = false, op.markers = true, op.marker_radius_px = 6;
  op.x = {r.operating.recall}, op.y = {r.operating.precision};
  series.push_back(op);
  if (!r.visual.empty()) {
    series.push_back(CurveSeries(r.visual, "visual stage 1 alone (ORB bag of words, eta)", "#2ca02c"));
    PlotSeries vop = op;
    vop.label = Fmt("visual stage 1 at eta >= %.2f", r.visual_operating.threshold);
    vop.color = "#17becf";
    vop.x = {r.visual_operating.recall}, vop.y = {r.visual_operating.precision};
    series.push_back(vop);
  }
  PlotOptions o;
  o.title = "loop detection precision / recall (truth revisits)";
  o.x_label = "recall", o.y_label = "precision";
  o.x_min = 0.0, o.x_max = 1.0, o.y_min = 0.0, o.y_max = 1.02;
  o.legend_above = true;
  return LinePlotSvg(series, o);
}

namespace {

Status WriteCurves(const std::string& path, const LoopPrResult& r) {
  std::ofstream out(path);
  out << "curve,threshold,precision,recall,tp,fp\n";
  auto rows = [&](const char* name, const std::vector<PrPoint>& curve) {
    for (const PrPoint& p : curve)
      out << name << ',' << Num(p.threshold) << ',' << Num(p.precision) << ',' << Num(p.recall) << ',' << p.tp << ','
          << p.fp << '\n';
  };
  rows("stage1", r.stage1);
  rows("stage2", r.stage2);
  rows("both", r.both);
  rows("operating", {r.operating});
  rows("visual", r.visual);  // descending eta: a detection is eta >= threshold
  if (r.visual_absent.empty()) rows("visual_operating", {r.visual_operating});
  return out ? Status::Ok() : Status::Error(path + ": write failed");
}

Status WriteQueries(const std::string& path, const LoopPrResult& r) {
  std::ofstream out(path);
  out << "query_id,t_query_s,positive,stage1_match,stage1_distance,stage1_true,stage1_truth_distance_m,"
         "stage1_truth_overlap,stage2_match,stage2_verified,stage2_fitness_m,stage2_true,stage2_truth_distance_m,"
         "stage2_truth_overlap,both_verified,both_fitness_m,both_true,visual_match,visual_eta,visual_raw_score,"
         "visual_true,visual_truth_distance_m,visual_truth_overlap\n";
  for (const LoopQueryOutcome& q : r.queries)
    out << q.query_id << ',' << Num(q.t_query_s) << ',' << q.positive << ',' << q.stage1_match << ','
        << Num(q.stage1_distance) << ',' << q.stage1_true << ',' << Num(q.stage1_truth_distance_m) << ','
        << Num(q.stage1_truth_overlap) << ',' << q.stage2_match << ',' << q.stage2_verified << ','
        << Num(q.stage2_fitness_m) << ',' << q.stage2_true << ',' << Num(q.stage2_truth_distance_m) << ','
        << Num(q.stage2_truth_overlap) << ',' << q.both_verified << ',' << Num(q.both_fitness_m) << ','
        << q.both_true << ',' << q.visual_match << ',' << Num(q.visual_eta) << ',' << Num(q.visual_raw_score)
        << ',' << q.visual_true << ',' << Num(q.visual_truth_distance_m) << ',' << Num(q.visual_truth_overlap)
        << '\n';
  return out ? Status::Ok() : Status::Error(path + ": write failed");
}

Status WriteLoopChecks(const std::string& path, const graph::LoopClosureState& state,
                       const std::vector<LoopTruthCheck>& checks) {
  std::ofstream out(path);
  out << "query_id,match_id,t_query_s,t_match_s,truth_distance_m,truth_overlap,error_m,error_deg,correct,rejected\n";
  for (size_t i = 0; i < checks.size() && i < state.loops.size(); ++i) {
    const graph::LoopRecord& l = state.loops[i];
    const LoopTruthCheck& c = checks[i];
    out << l.query_id << ',' << l.match_id << ',' << Num(l.t_query_s) << ',' << Num(l.t_match_s) << ','
        << Num(c.truth_distance_m) << ',' << Num(c.truth_overlap) << ',' << Num(c.error_m) << ','
        << Num(c.error_rad * 180.0 / M_PI) << ',' << c.correct << ',' << l.rejected << '\n';
  }
  return out ? Status::Ok() : Status::Error(path + ": write failed");
}

std::vector<std::string> CurveRow(const char* name, const std::vector<PrPoint>& curve) {
  const PrPoint last = curve.empty() ? PrPoint{} : curve.back();
  return {name, Fmt("%.3f", RecallAtPrecision1(curve)), Fmt("%.3f", last.precision), Fmt("%.3f", last.recall)};
}

// The visual stage 1's lines of the summary table: its operating point, or why there is no curve.
std::vector<std::pair<std::string, std::string>> VisualSummary(const LoopPrResult& r) {
  if (!r.visual_absent.empty()) return {{"visual stage 1 alone", "not rated: " + r.visual_absent}};
  const PrPoint& v = r.visual_operating;
  const std::string at = Fmt("visual stage 1 alone at eta >= %.2f (the seed's): ", v.threshold);
  return {{"keyframes with a bag-of-words vector", std::to_string(r.visual_keyframes)},
          {at + "precision", Fmt("%.3f", v.precision)},
          {at + "recall", Fmt("%.3f", v.recall)},
          {at + "true / false detections", std::to_string(v.tp) + " / " + std::to_string(v.fp)}};
}

}  // namespace

Status WriteLoopPrOutputs(const std::string& out_dir, const std::string& title, const LoopPrResult& r,
                          const graph::LoopClosureState& state, const std::vector<LoopTruthCheck>& checks) {
  if (Status s = WriteCurves(out_dir + "/loop_pr.csv", r); !s) return s;
  if (Status s = WriteQueries(out_dir + "/loop_queries.csv", r); !s) return s;
  if (Status s = WriteLoopChecks(out_dir + "/loops_truth.csv", state, checks); !s) return s;
  LoopVerdicts verdicts;
  std::vector<std::vector<std::string>> rows;
  for (size_t i = 0; i < checks.size() && i < state.loops.size(); ++i) {
    const LoopTruthCheck& c = checks[i];
    verdicts.push_back(c.correct);
    rows.push_back({std::to_string(state.loops[i].query_id) + " -> " + std::to_string(state.loops[i].match_id),
                    Fmt("%.2f", c.truth_distance_m), Fmt("%.2f", c.truth_overlap), Fmt("%.3f", c.error_m),
                    Fmt("%.2f", c.error_rad * 180.0 / M_PI), c.correct ? "yes" : "NO",
                    state.loops[i].rejected ? "rejected" : "kept"});
  }
  HtmlReport html("Loop detection: " + title);
  html.BeginSection("pr", "Precision / recall against truth revisits");
  std::vector<std::pair<std::string, std::string>> summary = {
      {"queries (keyframes with an eligible earlier keyframe)", std::to_string(r.queries.size())},
      {"positives (an eligible true revisit exists)", std::to_string(r.positives)},
      {"operating point: precision", Fmt("%.3f", r.operating.precision)},
      {"operating point: recall", Fmt("%.3f", r.operating.recall)},
      {"operating point: true / false detections",
       std::to_string(r.operating.tp) + " / " + std::to_string(r.operating.fp)},
      {"GICP time, all queries [s]", Fmt("%.1f", r.verify_time_s)}};
  for (auto& line : VisualSummary(r)) summary.push_back(std::move(line));
  html.KeyValueTable(summary);
  html.Figure(LoopPrSvg(r), "Each detector proposes one earlier keyframe per query; sweeping its score's gate traces "
                            "the curve (the visual stage 1's from high eta down). The operating point is the loop closer's default gates; "
                            "the visual stage 1's is the seed's eta >= 0.35 with the raw-score floor.");
  html.Table({"detector", "recall at precision 1", "precision (gate open)", "recall (gate open)"},
             {CurveRow("stage 1 alone", r.stage1), CurveRow("stage 2 alone", r.stage2), CurveRow("both", r.both),
              r.visual_absent.empty() ? CurveRow("visual stage 1 alone (eta)", r.visual)
                                      : std::vector<std::string>{"visual stage 1 alone (eta)", "-", "-", "-"}});
  html.BeginSection("loops", "Loops the run accepted");
  int false_loops = 0, false_kept = 0;
  for (size_t i = 0; i < verdicts.size(); ++i)
    false_loops += verdicts[i] == 0, false_kept += verdicts[i] == 0 && !state.loops[i].rejected;
  html.Paragraph(std::to_string(state.loops.size()) + " loops accepted by stage 2, " + std::to_string(false_loops) +
                 " of them false (GICP's relative pose off the truth's by more than the bound; loops_truth.csv), " +
                 std::to_string(false_kept) + " of those kept by the pose graph (the others its chi2 test rejected).");
  html.Figure(LoopTopViewSvg(state, verdicts), "Keyframe positions before (odometry) and after the pose graph, with "
                                               "the loop edges between corrected positions.");
  html.Table({"loop (query -> match)", "truth distance [m]", "truth overlap", "pose error [m]", "pose error [deg]",
              "correct", "graph"},
             rows);
  return html.Write(out_dir + "/loops.html");
}

}  // namespace rotolidar::bench
