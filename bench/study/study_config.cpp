#include "bench/study/study_config.hpp"

#include <cmath>
#include <filesystem>
#include <set>

#include "core/io/yaml_util.hpp"

namespace rotolidar::bench {
namespace {

constexpr size_t kMaxPoints = 10000;  // a sweep beyond this is almost surely a typo in a list

bool ValidName(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') return false;
  return true;
}

/// A path in the study file: absolute as is, relative against the study file's folder.
std::string Relative(const std::string& study_path, const std::string& path) {
  std::filesystem::path p(path);
  if (p.is_relative()) p = std::filesystem::path(study_path).parent_path() / p;
  return p.lexically_normal().string();
}

template <typename T>
std::vector<T> GetList(const std::string& file, const YAML::Node& sweep, const std::string& key) {
  std::vector<T> out;
  const YAML::Node n = sweep[key];
  if (!n) return out;
  if (!n.IsSequence() || n.size() == 0)
    throw yaml::ParseError(yaml::Where(file, n) + "sweep." + key + ": expected a non-empty list of values");
  for (size_t i = 0; i < n.size(); ++i) {
    try {
      out.push_back(n[i].as<T>());
    } catch (const YAML::Exception&) {
      throw yaml::ParseError(yaml::Where(file, n[i]) + "sweep." + key + ": cannot read value '" +
                             (n[i].IsScalar() ? n[i].Scalar() : std::string("<non-scalar>")) + "'");
    }
  }
  return out;
}

/// A list of names mapped through `parse` (false = unknown name, reported with `allowed`).
template <typename T, typename Parse>
std::vector<T> GetNamed(const std::string& file, const YAML::Node& sweep, const std::string& key, Parse parse,
                        const std::string& allowed) {
  std::vector<T> out;
  const std::vector<std::string> names = GetList<std::string>(file, sweep, key);
  for (size_t i = 0; i < names.size(); ++i) {
    T value{};
    if (!parse(names[i], &value))
      throw yaml::ParseError(yaml::Where(file, sweep[key][i]) + "sweep." + key + ": unknown value '" + names[i] +
                             "' (" + allowed + ")");
    out.push_back(value);
  }
  return out;
}

bool ParseAxis(const std::string& name, sim::MotorAxis* axis) {
  for (sim::MotorAxis a : {sim::MotorAxis::kHorizontal, sim::MotorAxis::kVertical, sim::MotorAxis::kTilted})
    if (name == sim::MotorAxisName(a)) return *axis = a, true;
  return false;
}

void ThrowIfError(const Status& s) {
  if (!s) throw yaml::ParseError(s.message);
}

void ParseVariants(const std::string& file, const YAML::Node& n, const sim::SimConfig& base, StudySweep* sweep) {
  if (!n.IsMap() || n.size() == 0)
    throw yaml::ParseError(yaml::Where(file, n) + "sweep.variant: expected a mapping NAME: {sim config keys}");
  for (const auto& kv : n) {
    StudyVariant v{kv.first.as<std::string>(), base};
    if (!ValidName(v.name))
      throw yaml::ParseError(yaml::Where(file, kv.first) + "sweep.variant: name '" + v.name +
                             "' must be letters, digits, '_', '-' or '.'");
    if (!kv.second.IsNull()) ThrowIfError(sim::ParseSimConfig(file, kv.second, &v.sim));
    sweep->variants.push_back(std::move(v));
  }
}

StudySweep ParseSweep(const std::string& file, const YAML::Node& n, const sim::SimConfig& base) {
  yaml::CheckKeys(file, n, {"variant", "motor_speed_radps", "profile", "axis", "scene", "carrier", "seed"}, "sweep");
  StudySweep s;
  if (const YAML::Node v = n["variant"]) ParseVariants(file, v, base, &s);
  s.motor_speed_radps = GetList<double>(file, n, "motor_speed_radps");
  s.profiles = GetNamed<sim::MotorProfileType>(file, n, "profile", sim::ParseMotorProfileType,
                                               "constant, trapezoid, nodding or stop_and_go");
  s.axes = GetNamed<sim::MotorAxis>(file, n, "axis", ParseAxis, "horizontal, vertical or tilted");
  s.scenes = GetList<std::string>(file, n, "scene");
  s.carriers = GetNamed<sim::CarrierType>(file, n, "carrier", sim::CarrierTypeFromName,
                                          "scripted_loop, handheld, wheeled, car or kitti");
  s.seeds = GetList<uint64_t>(file, n, "seed");
  return s;
}

StudyPlot ParsePlot(const std::string& file, const YAML::Node& n) {
  StudyPlot p;
  if (n.IsScalar()) {
    p.metrics = {n.as<std::string>()};
    if (!FindStudyMetric(p.metrics[0]))
      throw yaml::ParseError(yaml::Where(file, n) + "plots: unknown metric '" + p.metrics[0] +
                             "' (docs/studies.md lists them)");
    return p;
  }
  if (!n.IsMap()) throw yaml::ParseError(yaml::Where(file, n) + "plots: an entry is a metric name or a mapping");
  yaml::CheckKeys(file, n, {"kind", "metric", "metrics", "x", "title"}, "plots");
  std::string kind = "line";
  yaml::Get(file, n, "kind", &kind);
  if (kind == "bars") p.kind = StudyPlotKind::kBars;
  else if (kind != "line") throw yaml::ParseError(yaml::Where(file, n["kind"]) + "plots.kind: line or bars");
  if (n["metric"] && n["metrics"])
    throw yaml::ParseError(yaml::Where(file, n) + "plots: give either metric or metrics, not both");
  if (n["metric"]) p.metrics = {std::string()}, yaml::Get(file, n, "metric", &p.metrics[0]);
  yaml::Get(file, n, "metrics", &p.metrics);
  yaml::Get(file, n, "x", &p.x);
  yaml::Get(file, n, "title", &p.title);
  for (const std::string& m : p.metrics)
    if (!FindStudyMetric(m))
      throw yaml::ParseError(yaml::Where(file, n) + "plots: unknown metric '" + m + "' (docs/studies.md lists them)");
  return p;
}

void ParseStudy(const std::string& file, const YAML::Node& root, StudyConfig* c) {
  yaml::CheckKeys(file, root, {"name", "sim", "duration_s", "slam_config", "sweep", "plots"}, "study");
  yaml::Get(file, root, "name", &c->name);
  if (const YAML::Node n = root["sim"]) {
    if (n.IsScalar()) ThrowIfError(sim::LoadSimConfig(Relative(file, n.as<std::string>()), &c->base));
    else ThrowIfError(sim::ParseSimConfig(file, n, &c->base));
  }
  yaml::Get(file, root, "duration_s", &c->base.duration_s);
  if (root["slam_config"]) {
    yaml::Get(file, root, "slam_config", &c->slam_config_path);
    c->slam_config_path = Relative(file, c->slam_config_path);
  }
  // Variants start from the base with the study's duration already applied.
  if (const YAML::Node n = root["sweep"]) c->sweep = ParseSweep(file, n, c->base);
  if (const YAML::Node n = root["plots"]) {
    if (!n.IsSequence()) throw yaml::ParseError(yaml::Where(file, n) + "plots: expected a list");
    c->plots.clear();
    for (const YAML::Node& p : n) c->plots.push_back(ParsePlot(file, p));
  }
}

bool Swept(const StudySweep& s, const std::string& x) {
  if (x == "motor_speed_radps") return !s.motor_speed_radps.empty();
  if (x == "seed") return !s.seeds.empty();
  return false;
}

}  // namespace

size_t StudySweep::NumPoints() const {
  size_t n = 1;
  for (size_t k : {variants.size(), motor_speed_radps.size(), profiles.size(), axes.size(), scenes.size(),
                   carriers.size(), seeds.size()})
    if (k > 0) n *= k;
  return n;
}

const std::vector<StudyMetric>& StudyMetrics() {
  static const std::vector<StudyMetric> m = {
      {"ate_rmse_m", "ATE RMSE [m]", {"/ape_translation_m/rmse"}},
      {"coverage_total", "coverage, all surfaces [-]", {"/map/coverage/total/coverage"}},
      {"coverage_wall", "coverage, walls [-]", {"/map/coverage/wall/coverage"}},
      {"coverage_floor", "coverage, floor [-]", {"/map/coverage/floor/coverage"}},
      {"coverage_ceiling", "coverage, ceiling [-]", {"/map/coverage/ceiling/coverage"}},
      {"coverage_other", "coverage, other surfaces [-]", {"/map/coverage/other/coverage"}},
      {"completeness_total", "completeness, all surfaces [-]", {"/map/coverage/total/completeness"}},
      {"completeness_wall", "completeness, walls [-]", {"/map/coverage/wall/completeness"}},
      {"completeness_floor", "completeness, floor [-]", {"/map/coverage/floor/completeness"}},
      {"completeness_ceiling", "completeness, ceiling [-]", {"/map/coverage/ceiling/completeness"}},
      {"map_to_truth_median_m", "map-to-truth distance, median [m]", {"/map/map_to_truth_m/median"}},
      {"deskew_median_m", "deskew error, median [m]", {"/deskew_error_m/median"}},
      {"map_points", "map points [-]", {"/slam/map_points"}},
      {"slam_median_scan_ms", "SLAM time per scan, median [ms]", {"/slam/median_scan_ms"}},
      {"slam_realtime_factor", "SLAM real-time factor [x]", {"/slam/realtime_factor"}},
      {"sim_wall_s", "simulation wall time [s]", {"/sim/wall_time_s"}},
      {"slam_wall_s", "SLAM wall time [s]", {"/slam/wall_time_s"}},
      {"runtime_s", "point runtime (sim + SLAM + metrics) [s]", {}},
  };
  return m;
}

const StudyMetric* FindStudyMetric(const std::string& name) {
  for (const StudyMetric& m : StudyMetrics())
    if (m.name == name) return &m;
  return nullptr;
}

std::vector<StudyPlot> DefaultStudyPlots(const StudySweep& sweep) {
  std::vector<StudyPlot> plots;
  const bool line = !sweep.motor_speed_radps.empty();
  for (const char* metric : {"coverage_total", "ate_rmse_m", "deskew_median_m", "runtime_s"}) {
    StudyPlot p;
    p.kind = line ? StudyPlotKind::kLine : StudyPlotKind::kBars;
    p.metrics = {metric};
    plots.push_back(p);
  }
  return plots;
}

bool StudyConfig::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = "StudyConfig: " + m;
    return false;
  };
  if (name.empty()) return fail("name must not be empty");
  std::string why;
  if (!base.Validate(&why)) return fail("sim: " + why);
  std::set<std::string> names;
  for (const StudyVariant& v : sweep.variants) {
    if (!ValidName(v.name)) return fail("sweep.variant '" + v.name + "': letters, digits, '_', '-' or '.'");
    if (!names.insert(v.name).second) return fail("sweep.variant '" + v.name + "' is given twice");
    if (!v.sim.Validate(&why)) return fail("sweep.variant " + v.name + ": " + why);
  }
  for (double w : sweep.motor_speed_radps)
    if (!std::isfinite(w) || std::abs(w) > 200.0) return fail("sweep.motor_speed_radps: finite, |w| <= 200 rad/s");
  for (const std::string& s : sweep.scenes)
    if (s.empty()) return fail("sweep.scene: empty scene name");
  if (sweep.NumPoints() > kMaxPoints) return fail("the sweep has more than 10000 points");
  for (const StudyPlot& p : plots) {
    if (p.metrics.empty()) return fail("plots: an entry without metrics");
    for (const std::string& m : p.metrics)
      if (!FindStudyMetric(m)) return fail("plots: unknown metric '" + m + "' (docs/studies.md lists them)");
    if (p.kind == StudyPlotKind::kLine && p.metrics.size() != 1) return fail("plots: a line plot takes one metric");
    if (p.kind == StudyPlotKind::kLine && !Swept(sweep, p.x))
      return fail("plots: line plot x '" + p.x + "' must be a swept axis (motor_speed_radps or seed)");
  }
  return true;
}

Status LoadStudyConfig(const std::string& path, StudyConfig* config) {
  StudyConfig c = *config;
  c.source_path = path;
  try {
    const YAML::Node root = yaml::LoadFile(path);
    if (!root.IsMap()) throw yaml::ParseError(yaml::Where(path, root) + "study: expected a mapping");
    ParseStudy(path, root, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {  // e.g. a map key that is not a scalar
    return Status::Error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(path + ": " + why);
  *config = c;
  return Status::Ok();
}

}  // namespace rotolidar::bench
