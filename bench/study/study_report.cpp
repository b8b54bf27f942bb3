#include "bench/study/study_report.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "bench/report/svg_plot.hpp"

namespace rotolidar::bench {
namespace {

std::string Num(double v) {
  if (!std::isfinite(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

size_t MetricIndex(const std::string& name) {
  for (size_t i = 0; i < StudyMetrics().size(); ++i)
    if (StudyMetrics()[i].name == name) return i;
  return 0;  // unreachable for validated configs
}

/// The point's parameters as (column, value), swept or not.
std::vector<std::pair<std::string, std::string>> Parameters(const StudyPoint& p) {
  return {{"variant", p.variant},
          {"scene", p.sim.scene},
          {"carrier", sim::CarrierTypeName(p.sim.carrier.type)},
          {"axis", sim::MotorAxisName(p.sim.rig_model.motor.axis)},
          {"profile", sim::ToString(p.sim.motor.profile.type)},
          {"motor_speed_radps", Num(p.sim.motor.profile.speed_radps)},
          {"seed", std::to_string(p.sim.seed)},
          {"duration_s", Num(p.sim.duration_s)}};
}

/// "axis=value, ..." over the swept axes not in `skip`; just the value when one axis is left, "all points" when
/// none is.
std::string GroupLabel(const StudyPoint& p, const std::set<std::string>& skip) {
  std::string label, single;
  int axes = 0;
  for (const auto& [axis, value] : p.swept) {
    if (skip.count(axis)) continue;
    label += (label.empty() ? "" : ", ") + axis + "=" + value;
    single = value, ++axes;
  }
  return axes == 0 ? "all points" : axes == 1 ? single : label;
}

struct MeanStd {
  double mean = kStudyNaN, std = kStudyNaN;
};
MeanStd Summarize(const std::vector<double>& v) {
  MeanStd m;
  if (v.empty()) return m;
  double s = 0, s2 = 0;
  for (double x : v) s += x;
  m.mean = s / v.size();
  for (double x : v) s2 += (x - m.mean) * (x - m.mean);
  m.std = v.size() > 1 ? std::sqrt(s2 / (v.size() - 1)) : kStudyNaN;
  return m;
}

double Value(const StudyPointResult& r, size_t metric) {
  return r.state == PointState::kFailed ? kStudyNaN : r.metrics[metric];
}

std::string LineSvg(const StudyPlot& plot, const StudyResult& result, const std::string& title) {
  const size_t m = MetricIndex(plot.metrics[0]);
  const std::set<std::string> skip = {plot.x == "motor_speed_radps" ? "speed" : plot.x, "seed"};
  std::map<std::string, std::map<double, std::vector<double>>> groups;  // label -> x -> values over seeds
  std::vector<std::string> order;
  for (const StudyPointResult& r : result.points) {
    const std::string label = GroupLabel(r.point, skip);
    if (!groups.count(label)) order.push_back(label);
    const double x = plot.x == "seed" ? double(r.point.sim.seed) : r.point.sim.motor.profile.speed_radps;
    std::vector<double>& values = groups[label][x];
    if (std::isfinite(Value(r, m))) values.push_back(Value(r, m));
  }
  std::vector<PlotSeries> series;
  for (const std::string& label : order) {
    PlotSeries s;
    s.label = order.size() > 1 ? label : plot.metrics[0];
    s.markers = true;
    bool errors = false;
    for (const auto& [x, values] : groups[label]) {
      const MeanStd ms = Summarize(values);
      s.x.push_back(x), s.y.push_back(ms.mean), s.y_err.push_back(std::isfinite(ms.std) ? ms.std : 0.0);
      errors |= std::isfinite(ms.std);
    }
    if (!errors) s.y_err.clear();
    series.push_back(std::move(s));
  }
  PlotOptions o;
  o.title = title;
  o.x_label = plot.x == "seed" ? "seed [-]" : "motor speed [rad/s]";
  o.y_label = StudyMetrics()[m].label;
  o.y_include_zero = true;
  o.legend_above = true;  // one line per combination: keep the legend off the data
  return LinePlotSvg(series, o);
}

/// The "[unit]" at the end of a metric's label.
std::string Unit(const std::string& metric) {
  const std::string& label = StudyMetrics()[MetricIndex(metric)].label;
  return label.substr(std::min(label.size(), label.rfind('[')));
}

std::string BarsSvg(const StudyPlot& plot, const StudyResult& result, const std::string& title) {
  std::vector<std::string> categories;
  std::map<std::string, std::vector<const StudyPointResult*>> members;  // category -> points (over seeds)
  for (const StudyPointResult& r : result.points) {
    const std::string label = GroupLabel(r.point, {"seed"});
    if (!members.count(label)) categories.push_back(label);
    members[label].push_back(&r);
  }
  std::vector<BarSeries> series;
  bool same_unit = true;
  for (const std::string& name : plot.metrics) {
    BarSeries b;
    b.label = name;
    const size_t m = MetricIndex(name);
    bool errors = false;
    for (const std::string& c : categories) {
      std::vector<double> values;
      for (const StudyPointResult* r : members[c])
        if (std::isfinite(Value(*r, m))) values.push_back(Value(*r, m));
      const MeanStd ms = Summarize(values);
      b.values.push_back(ms.mean), b.errors.push_back(std::isfinite(ms.std) ? ms.std : 0.0);
      errors |= std::isfinite(ms.std);
    }
    if (!errors) b.errors.clear();
    same_unit &= Unit(name) == Unit(plot.metrics[0]);
    series.push_back(std::move(b));
  }
  PlotOptions o;
  o.title = title;
  o.y_label = plot.metrics.size() == 1 ? StudyMetrics()[MetricIndex(plot.metrics[0])].label
                                       : "value " + (same_unit ? Unit(plot.metrics[0]) : std::string());
  o.y_include_zero = true;
  o.legend_above = true;  // bars reach the top of the plot area: a legend inside would cover the tallest
  return BarChartSvg(categories, series, o);
}

std::string PlotTitle(const StudyPlot& p) {
  if (!p.title.empty()) return p.title;
  std::string t;
  for (const std::string& m : p.metrics) t += (t.empty() ? "" : ", ") + m;
  return p.kind == StudyPlotKind::kLine ? t + " vs " + p.x : t;
}

}  // namespace

std::string StudyCsv(const StudyResult& result) {
  std::ostringstream os;
  os << "point,state,exit_code";
  for (const auto& [name, value] : Parameters(StudyPoint{})) os << "," << name;
  for (const StudyMetric& m : StudyMetrics()) os << "," << m.name;
  os << "\n";
  for (const StudyPointResult& r : result.points) {
    os << CsvField(r.point.id) << "," << PointStateName(r.state) << "," << r.exit_code;
    for (const auto& [name, value] : Parameters(r.point)) os << "," << CsvField(value);
    for (double v : r.metrics) os << "," << Num(v);
    os << "\n";
  }
  return os.str();
}

std::vector<StudyFigure> StudyFigures(const StudyConfig& config, const StudyResult& result) {
  const std::vector<StudyPlot> plots = config.plots.empty() ? DefaultStudyPlots(config.sweep) : config.plots;
  std::vector<StudyFigure> figures;
  for (size_t i = 0; i < plots.size(); ++i) {
    const StudyPlot& p = plots[i];
    StudyFigure f;
    char prefix[32];
    std::snprintf(prefix, sizeof(prefix), "%02zu_", i + 1);
    f.file_name = prefix + p.metrics[0] + (p.kind == StudyPlotKind::kBars ? "_bars" : "_vs_" + p.x) + ".svg";
    f.title = PlotTitle(p);
    f.svg = p.kind == StudyPlotKind::kLine ? LineSvg(p, result, f.title) : BarsSvg(p, result, f.title);
    figures.push_back(std::move(f));
  }
  return figures;
}

}  // namespace rotolidar::bench
