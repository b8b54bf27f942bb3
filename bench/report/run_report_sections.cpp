#include "bench/report/run_report_sections.hpp"


#include <algorithm>
#include <cmath>

#include "bench/metrics/coverage.hpp"
#include "bench/report/svg_plot.hpp"
#include "bench/report/svg_raster.hpp"
#include "bench/run/scan_health.hpp"

namespace rotolidar::bench::report {
namespace {

constexpr const char* kTruthColor = "#222222";
constexpr const char* kEstimateColor = "#1f77b4";

PlotSeries XySeries(const Trajectory& t, const std::string& label, const std::string& color) {
  PlotSeries s;
  s.label = label;
  s.color = color;
  for (const StampedPose& p : t) {
    s.x.push_back(p.T_ref_body.translation().x());
    s.y.push_back(p.T_ref_body.translation().y());
  }
  return s;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double f = q * double(v.size() - 1);
  const size_t i = size_t(f);
  return i + 1 < v.size() ? v[i] + (f - double(i)) * (v[i + 1] - v[i]) : v[i];
}

/// Robust top-view limits of points: 0.2 / 99.8 % quantiles per axis, so a few far strays do not shrink the
/// picture; widened to include `also` (the trajectory).
void RobustLimits(const std::vector<Eigen::Vector2d>& xy, const std::vector<PlotSeries>& also, PlotOptions* o) {
  if (xy.size() < 100) return;
  std::vector<double> xs, ys;
  for (const Eigen::Vector2d& p : xy) xs.push_back(p.x()), ys.push_back(p.y());
  double x0 = Quantile(xs, 0.002), x1 = Quantile(xs, 0.998), y0 = Quantile(ys, 0.002), y1 = Quantile(ys, 0.998);
  for (const PlotSeries& s : also)
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]), y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
  const double m = 0.04 * std::max(x1 - x0, y1 - y0);
  o->x_min = x0 - m, o->x_max = x1 + m, o->y_min = y0 - m, o->y_max = y1 + m;
}

double T0(const RunReportInput& in) { return in.slam->trajectory.empty() ? 0.0 : in.slam->trajectory.front().t_s; }

/// The run's problem stretches as shaded spans (red: registration failed, orange: degenerate), relative to t0.
std::vector<XSpan> ProblemSpans(const RunReportInput& in, double t0) {
  std::vector<XSpan> spans;
  for (const ScanProblemStretch& s : AssessScanHealth(in.slam->scans).stretches)
    spans.push_back({s.t_start_s - t0, s.t_end_s - t0,
                     s.problem == ScanProblem::kNotConverged ? "#d62728" : "#ff7f0e"});
  return spans;
}

}  // namespace

void AddTrajectorySection(const RunReportInput& in, HtmlReport* html) {
  const RunEvaluation& ev = *in.evaluation;
  PlotOptions o;
  o.x_label = "x [m]";
  o.y_label = "y [m]";
  o.equal_aspect = true;
  o.legend_above = true;
  o.width_px = 620;
  o.height_px = 500;
  std::vector<PlotSeries> series;
  if (ev.has_truth) {
    html->BeginSection("trajectory", "Trajectory (top view, scene frame)");
    o.title = "estimate (SE(3)-aligned) vs truth";
    series.push_back(XySeries(ev.truth, "truth", kTruthColor));
    series.push_back(XySeries(ev.estimate_aligned, "estimate", kEstimateColor));
    series.back().dashed = true;
  } else {
    html->BeginSection("trajectory", "Trajectory (top view, SLAM world frame)");
    o.title = "estimate (no truth)";
    series.push_back(XySeries(in.slam->trajectory, "estimate", kEstimateColor));
  }
  PlotSeries start;
  start.label = "start";
  start.color = "#2ca02c";
  start.line = false;
  start.markers = true;
  start.marker_radius_px = 5;
  if (!series.back().x.empty()) start.x = {series.back().x.front()}, start.y = {series.back().y.front()};
  series.push_back(start);
  html->Figure(LinePlotSvg(series, o),
               ev.has_truth ? "Base positions at each scan start; the estimate is mapped into the scene frame by the "
                              "SE(3) Umeyama alignment used for the APE."
                            : "Base positions at each scan start in the SLAM world (the base frame at the first scan).");
}

void AddApeSection(const RunReportInput& in, HtmlReport* html) {
  const RunEvaluation& ev = *in.evaluation;
  if (!ev.has_truth) return;
  html->BeginSection("ape", "Absolute pose error over time");
  PlotSeries s;
  s.label = "APE (translation)";
  const double t0 = T0(in);
  for (size_t i = 0; i < std::min(ev.estimate_aligned.size(), ev.ape.errors.size()); ++i) {
    s.x.push_back(ev.estimate_aligned[i].t_s - t0);
    s.y.push_back(ev.ape.errors[i]);
  }
  PlotOptions o;
  o.title = "APE per pose, SE(3) Umeyama alignment";
  o.x_label = "time since the first scan [s]";
  o.y_label = "APE [m]";
  o.y_include_zero = true;
  o.width_px = 760;
  o.height_px = 320;
  o.legend = false;
  o.hlines = {{ev.ape.stats.rmse, "RMSE " + Fmt("%.4f m", ev.ape.stats.rmse), "#d62728"},
              {ev.ape.stats.median, "median " + Fmt("%.4f m", ev.ape.stats.median), "#7f7f7f"}};
  o.xspans = ProblemSpans(in, t0);
  html->Figure(LinePlotSvg({s}, o), "Translation error of each pose after alignment (evo's APE, trans_part), " +
                                        std::to_string(ev.ape.num_associated) + " poses. Shaded: scans whose "
                                        "registration failed (red) or was degenerate (orange).");
}

void AddRpeSection(const RunReportInput& in, HtmlReport* html) {
  const RunEvaluation& ev = *in.evaluation;
  if (!ev.has_truth) return;
  html->BeginSection("rpe", "Relative pose error");
  if (!ev.rpe.status.ok || ev.rpe.errors.empty()) {
    html->Note("RPE not available: " + ev.rpe.status.message);
    return;
  }
  HistogramOptions h;
  h.bins = 30;
  h.min = 0.0;
  PlotOptions o;
  o.title = "translation RPE over " + ev.rpe_delta + " (" + std::to_string(ev.rpe.errors.size()) + " pairs)";
  o.x_label = "RPE [m]";
  o.width_px = 620;
  o.height_px = 320;
  o.vlines = {{ev.rpe.stats.rmse, "RMSE", "#d62728"}, {ev.rpe.stats.median, "median", "#555555"}};
  html->Figure(HistogramSvg(ev.rpe.errors, h, o),
               "Translation part of the relative error between pose pairs " + ev.rpe_delta +
                   " apart along the estimated path (evo_rpe --all_pairs); alignment-free.");
}

std::vector<StageTiming> ComputeStageTimings(const std::vector<ScanReport>& scans) {
  struct Member {
    const char* name;
    double ScanTimings::*ms;
  };
  const Member members[] = {{"deskew", &ScanTimings::deskew_ms},     {"preprocess", &ScanTimings::preprocess_ms},
                            {"features", &ScanTimings::features_ms}, {"register", &ScanTimings::register_ms},
                            {"fuse", &ScanTimings::fuse_ms},         {"map", &ScanTimings::map_ms},
                            {"total", &ScanTimings::total_ms}};
  std::vector<StageTiming> out;
  bool any = false;
  for (const Member& m : members) {
    std::vector<double> v;
    for (const ScanReport& r : scans) v.push_back(r.timings.*(m.ms));
    StageTiming t;
    t.stage = m.name;
    t.median_ms = Quantile(v, 0.5), t.p95_ms = Quantile(v, 0.95);
    for (double x : v) t.mean_ms += x / double(v.size()), t.max_ms = std::max(t.max_ms, x);
    any = any || t.max_ms > 0;
    out.push_back(t);
  }
  return any ? out : std::vector<StageTiming>{};
}

void AddHealthSection(const RunReportInput& in, HtmlReport* html) {
  const ScanHealth h = AssessScanHealth(in.slam->scans);
  html->BeginSection("health", "Registration problems");
  if (h.stretches.empty()) {
    html->Note("none: every attempted registration converged and none was degenerate (" + std::to_string(h.scans) +
               " scans)");
    return;
  }
  const double t0 = T0(in);
  std::vector<std::vector<std::string>> rows;
  for (const ScanProblemStretch& s : h.stretches) {
    if (rows.size() == 50) break;
    rows.push_back({ScanProblemName(s.problem), Fmt("%.2f", s.t_start_s - t0), Fmt("%.2f", s.t_end_s - t0),
                    std::to_string(s.scans()), s.reason});
  }
  html->Table({"problem", "from [s]", "to [s]", "scans", "reason"}, rows,
              std::to_string(h.not_converged) + " of " + std::to_string(h.scans) + " scans did not converge, " +
                  std::to_string(h.degenerate) + " were degenerate (the IMU held the unobserved directions)" +
                  (h.stretches.size() > rows.size() ? "; the first 50 stretches (all: metrics.json)" : ""));
}

void AddTimingSection(const RunReportInput& in, HtmlReport* html) {
  const std::vector<ScanReport>& scans = in.slam->scans;
  if (scans.empty()) return;
  html->BeginSection("timing", "Runtime");
  PlotSeries s;
  s.label = "time per scan";
  std::vector<double> periods;
  for (const ScanReport& r : scans) {
    s.x.push_back(r.t_start_s - scans.front().t_start_s);
    s.y.push_back(r.timings.total_ms);
    periods.push_back(1e3 * (r.t_end_s - r.t_start_s));
  }
  PlotOptions o;
  o.title = "processing time per scan";
  o.x_label = "time since the first scan [s]";
  o.y_label = "processing time [ms]";
  o.y_include_zero = true;
  o.legend = false;
  o.width_px = 760;
  o.height_px = 300;
  const double budget_ms = Quantile(periods, 0.5);
  o.hlines = {{budget_ms, "real-time budget (median scan span " + Fmt("%.0f ms)", budget_ms), "#d62728"}};
  o.xspans = ProblemSpans(in, scans.front().t_start_s);
  html->Figure(LinePlotSvg({s}, o), "Wall time of the estimator's Process for each scan; below the red line the "
                                    "core keeps up with the data.");
  const std::vector<StageTiming> stages = ComputeStageTimings(scans);
  if (stages.empty()) {
    html->Note("per-stage timings not available (the estimator reported none)");
    return;
  }
  std::vector<std::vector<std::string>> rows;
  BarSeries mean{"mean", {}, {}, ""};
  std::vector<std::string> names;
  for (const StageTiming& t : stages) {
    rows.push_back({t.stage, Fmt("%.2f", t.median_ms), Fmt("%.2f", t.mean_ms), Fmt("%.2f", t.p95_ms),
                    Fmt("%.2f", t.max_ms)});
    if (t.stage == "total") continue;
    names.push_back(t.stage);
    mean.values.push_back(t.mean_ms);
  }
  html->Table({"stage", "median [ms]", "mean [ms]", "p95 [ms]", "max [ms]"}, rows, "per-stage wall time per scan");
  PlotOptions b;
  b.title = "mean time per stage";
  b.y_label = "time per scan [ms]";
  b.width_px = 520;
  b.height_px = 300;
  b.legend = false;
  html->Figure(BarChartSvg(names, {mean}, b), "Mean wall time of each pipeline stage per scan.");
}

void AddMapSection(const RunReportInput& in, HtmlReport* html) {
  const RunEvaluation& ev = *in.evaluation;
  if (ev.map_points.empty()) return;
  html->BeginSection("map", ev.has_map_metrics ? "Map accuracy (top view)" : "Map (top view)");
  std::vector<Eigen::Vector2d> xy;
  std::vector<double> values;
  xy.reserve(ev.map_points.size());
  const bool by_error = ev.has_map_metrics && ev.map.point_distance_m.size() == ev.map_points.size();
  for (size_t i = 0; i < ev.map_points.size(); ++i) {
    xy.emplace_back(ev.map_points[i].x(), ev.map_points[i].y());
    values.push_back(by_error ? double(ev.map.point_distance_m[i]) : double(ev.map_points[i].z()));
  }
  TopViewOptions t;
  PlotOptions o;
  o.x_label = "x [m]";
  o.y_label = "y [m]";
  o.width_px = 700;
  o.height_px = 540;
  o.legend_above = true;
  if (by_error) {
    t.colorbar_label = "map-to-truth distance [m]";
    t.value_min = 0.0;
    o.title = "map coloured by distance to the true surfaces";
  } else {
    t.colormap = Colormap::kTurbo;
    t.colorbar_label = "height z [m]";
    o.title = "map coloured by height";
  }
  // Red shows on viridis (no red in it); black on turbo (no black in it).
  std::vector<PlotSeries> overlay = {XySeries(ev.has_truth ? ev.estimate_aligned : in.slam->trajectory, "trajectory",
                                              by_error ? "#e41a1c" : "#000000")};
  overlay.back().line_width_px = 1.2;
  RobustLimits(xy, overlay, &o);
  html->Figure(PointTopViewSvg(xy, values, t, o, overlay),
               std::to_string(ev.map_points.size()) + " map points, " +
                   (ev.map_in_scene_frame ? "scene frame (SE(3) alignment of the APE)" : "SLAM world frame") +
                   "; each pixel shows the mean over the points above it.");
  if (ev.has_dynamic && ev.dynamic.returns_seen > 0)  // docs/metrics.md, 'Dynamic objects in the map'
    html->Paragraph(DynamicShareLine(ev.dynamic) + Fmt(": map points farther than %g m from the static scene",
                                                       ev.dynamic_config.static_clearance_m) +
                    Fmt(" and within %g m of a return the sim saw from a walker or car.",
                        ev.dynamic_config.hit_radius_m));
  if (!by_error) return;
  std::vector<double> d(ev.map.point_distance_m.begin(), ev.map.point_distance_m.end());
  HistogramOptions h;
  h.bins = 40;
  h.min = 0.0;
  h.max = std::max(1e-3, Quantile(d, 0.99));
  PlotOptions ho;
  ho.title = "map-to-truth distance per point";
  ho.x_label = "distance to the nearest scene triangle [m]";
  ho.y_label = "points";
  ho.width_px = 520;
  ho.height_px = 300;
  ho.vlines = {{ev.map.map_to_truth.median_m, "median", "#555555"}, {ev.map.map_to_truth.p95_m, "p95", "#d62728"}};
  html->Figure(HistogramSvg(d, h, ho), "Distances up to the 99th percentile; the rest are counted in the note.");
}

namespace {

/// Top view of the covered share of the surface samples: walls only, or the other non-ceiling surfaces.
std::string CoverageView(const RunEvaluation& ev, bool walls) {
  std::vector<Eigen::Vector2d> xy;
  std::vector<double> covered;
  for (const SurfaceSample& s : ev.map.samples) {
    if (s.surface_class == SurfaceClass::kCeiling || (s.surface_class == SurfaceClass::kWall) != walls) continue;
    xy.emplace_back(s.p_world.x(), s.p_world.y());
    covered.push_back(s.covered ? 1.0 : 0.0);
  }
  TopViewOptions t;
  t.colormap = Colormap::kRedYellowGreen;
  t.value_min = 0.0;
  t.value_max = 1.0;
  t.colorbar_label = "covered share";
  // One sample per cell for floors (finer cells alias with the sample grid); walls twice as coarse so that
  // their one-cell-wide lines stay visible.
  t.cell_m = (walls ? 2.0 : 1.0) * ev.map_config.sample_spacing_m;
  PlotOptions o;
  o.title = walls ? "walls: covered (green) vs missed (red)" : "floors and others: covered (green) vs missed (red)";
  o.x_label = "x [m]";
  o.y_label = "y [m]";
  o.width_px = 540;
  o.height_px = 440;
  return PointTopViewSvg(xy, covered, t, o);
}

}  // namespace

void AddCoverageSection(const RunReportInput& in, HtmlReport* html) {
  const RunEvaluation& ev = *in.evaluation;
  if (!ev.has_map_metrics) return;
  html->BeginSection("coverage", "Surface coverage");
  html->Figure(CoverageView(ev, false), "Floors and other upward-facing or sloped surfaces.");
  html->Figure(CoverageView(ev, true), "Walls: each pixel is the covered share over the wall's height.");
  html->Paragraph("Scene surfaces are sampled every " + Fmt("%.2f m", ev.map_config.sample_spacing_m) +
                  "; a sample is covered when a map point lies within " +
                  Fmt("%.2f m", ev.map_config.coverage_distance_m) + " of it. Ceilings are left out of the pictures.");
  const CoverageResult& c = ev.map.coverage;
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> names;
  BarSeries cov{"coverage", {}, {}, ""}, comp{"completeness (visible surfaces)", {}, {}, ""};
  for (int k = 0; k <= kNumSurfaceClasses; ++k) {
    const ClassCoverage& cc = k < kNumSurfaceClasses ? c.per_class[size_t(k)] : c.total;
    const std::string name = k < kNumSurfaceClasses ? SurfaceClassName(SurfaceClass(k)) : "total";
    if (cc.area_m2 <= 0) continue;
    rows.push_back({name, Fmt("%.1f", cc.area_m2), Fmt("%.1f", cc.covered_area_m2), Fmt("%.1f %%", 100 * cc.coverage),
                    c.has_visibility ? Fmt("%.1f", cc.visible_area_m2) : "-",
                    c.has_visibility ? Fmt("%.1f %%", 100 * cc.completeness) : "-"});
    names.push_back(name);
    cov.values.push_back(100 * cc.coverage);
    comp.values.push_back(100 * cc.completeness);
  }
  html->Table({"surface", "area [m²]", "covered [m²]", "coverage", "visible [m²]", "completeness"}, rows,
              "coverage per surface class (completeness: covered share of the surfaces visible from the path)");
  std::vector<BarSeries> bars = {cov};
  if (c.has_visibility) bars.push_back(comp);
  PlotOptions b;
  b.title = "coverage per surface class";
  b.y_label = "share of the area [%]";
  b.y_max = 100.0;
  b.legend_above = true;
  b.width_px = 520;
  b.height_px = 300;
  html->Figure(BarChartSvg(names, bars, b), "Coverage of all sampled surfaces and completeness of the visible ones.");
}

void AddElementsSection(const RunReportInput& in, HtmlReport* html) {
  const RunEvaluation& ev = *in.evaluation;
  if (!ev.has_map_metrics) return;
  html->BeginSection("elements", "Element geometry");
  if (ev.map.elements.empty()) {
    html->Note("the scene annotates no doors, windows or columns");
    return;
  }
  auto dim = [](bool ok, double v) { return ok ? Fmt("%.3f", v) : std::string("-"); };
  auto err = [](bool ok, double v) { return ok ? Fmt("%+.3f", v) : std::string("-"); };
  std::vector<std::vector<std::string>> rows;
  for (const ElementMeasurement& e : ev.map.elements)
    rows.push_back({e.name, e.type, Fmt("%.3f", e.true_width_m), dim(e.width_measured, e.width_m),
                    err(e.width_measured, e.width_error_m), Fmt("%.3f", e.true_height_m),
                    dim(e.height_measured, e.height_m), err(e.height_measured, e.height_error_m),
                    std::to_string(e.crop_points), e.message});
  html->Table({"element", "type", "true width [m]", "width [m]", "error [m]", "true height [m]", "height [m]",
               "error [m]", "points", "note"},
              rows, "measured vs true dimensions (bench/metrics/geometry_accuracy.hpp; docs/metrics.md)");
  const ElementSummary& s = ev.map.element_summary;
  html->Paragraph(std::to_string(s.widths_measured) + " of " + std::to_string(s.elements) + " widths and " +
                  std::to_string(s.heights_measured) + " heights measured; RMSE " + Fmt("%.3f m", s.rmse_m) +
                  " (width " + Fmt("%.3f m", s.width_rmse_m) + ", height " + Fmt("%.3f m", s.height_rmse_m) +
                  "), largest |error| " + Fmt("%.3f m", s.max_abs_error_m) + ".");
}

}  // namespace rotolidar::bench::report
