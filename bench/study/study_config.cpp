#include "bench/study/study_config.hpp"

#include <cmath>
#include <filesystem>
#include <set>

#include "core/io/yaml_fields.hpp"

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

void ThrowIfError(const Status& s) {
  if (!s) throw yaml::ParseError(s.message);
}

void ParseVariants(const std::string& file, const YAML::Node& n, const sim::SimConfig& base, StudySweep* sweep) {
  if (!n.IsMap() || n.size() == 0)
    throw yaml::ParseError(yaml::Where(file, n) + "sweep.variant: expected a mapping NAME: {sim config keys}");
  for (const auto& kv : n) {
    StudyVariant v{yaml::KeyName(file, kv.first, "sweep.variant"), base};
    if (!ValidName(v.name))
      throw yaml::ParseError(yaml::Where(file, kv.first) + "sweep.variant: name '" + v.name +
                             "' must be letters, digits, '_', '-' or '.'");
    if (!kv.second.IsNull()) ThrowIfError(sim::ParseSimConfig(file, kv.second, &v.sim));
    sweep->variants.push_back(std::move(v));
  }
}

/// The sweep replaces *sweep: its typed axes from the field list (every axis a non-empty list), its variants
/// (named sim configs over `base`) by hand.
void ParseSweep(const yaml::Section& at, const YAML::Node& n, const sim::SimConfig& base, StudySweep* sweep) {
  StudySweep s;
  yaml::Parse(at, n, &s, {"variant"});
  for (const auto& kv : n) {
    const std::string key = yaml::KeyName(at.file, kv.first, at.path);
    if (key != "variant" && (!kv.second.IsSequence() || kv.second.size() == 0))
      throw yaml::ParseError(yaml::Where(at.file, kv.second) + at.Field(key) + ": expected a non-empty list of values");
  }
  if (const YAML::Node v = n["variant"]) ParseVariants(at.file, v, base, &s);
  *sweep = std::move(s);
}

void CheckMetric(const std::string& file, const YAML::Node& at, const std::string& metric) {
  if (!FindStudyMetric(metric))
    throw yaml::ParseError(yaml::Where(file, at) + "plots: unknown metric '" + metric +
                           "' (docs/studies.md lists them)");
}

/// `metric: NAME`, the one-metric spelling of `metrics`.
void ReadOneMetric(const yaml::Section& at, const YAML::Node& n, std::vector<std::string>* metrics) {
  metrics->assign(1, std::string());
  yaml::ReadAs(at.file, n, at.path, &metrics->front());
}

/// A plot entry: a metric name (a line plot against motor speed) or a mapping of StudyPlot's fields.
StudyPlot ParsePlot(const yaml::Section& at, const YAML::Node& n) {
  StudyPlot p;
  if (n.IsScalar()) {
    p.metrics = {n.as<std::string>()};
    CheckMetric(at.file, n, p.metrics[0]);
    return p;
  }
  if (!n.IsMap()) throw yaml::ParseError(yaml::Where(at.file, n) + "plots: an entry is a metric name or a mapping");
  if (n["metric"] && n["metrics"])
    throw yaml::ParseError(yaml::Where(at.file, n) + "plots: give either metric or metrics, not both");
  yaml::Parse(at, n, &p);
  for (const std::string& m : p.metrics) CheckMetric(at.file, n, m);
  return p;
}

void ReadPlots(const yaml::Section& at, const YAML::Node& n, std::vector<StudyPlot>* plots) {
  if (!n.IsSequence()) throw yaml::ParseError(yaml::Where(at.file, n) + "plots: expected a list");
  plots->clear();
  for (const YAML::Node& p : n) plots->push_back(ParsePlot(at, p));
}

/// sim: a sim config file (relative to the study file) or an inline mapping, over the base.
Status ReadBaseSim(const yaml::Section& at, const YAML::Node& n, sim::SimConfig* base) {
  if (n.IsScalar()) return sim::LoadSimConfig(Relative(at.file, n.as<std::string>()), base);
  return sim::ParseSimConfig(at.file, n, base);
}

void ReadRelativePath(const yaml::Section& at, const YAML::Node& n, std::string* path) {
  yaml::ReadAs(at.file, n, at.path, path);
  *path = Relative(at.file, *path);
}

}  // namespace

// ---- the field lists (in the structs' namespace, so the generic visitors find them) ----

const yaml::EnumWordList<StudyPlotKind>& EnumWords(StudyPlotKind*) {
  static const yaml::EnumWordList<StudyPlotKind> words{{"line", StudyPlotKind::kLine}, {"bars", StudyPlotKind::kBars}};
  return words;
}

template <class V>
void Visit(V& v, StudySweep& s) {
  v("motor_speed_radps", &s.motor_speed_radps), v("profile", &s.profiles), v("axis", &s.axes);
  v("scene", &s.scenes), v("carrier", &s.carriers), v("seed", &s.seeds);
}

template <class V>
void Visit(V& v, StudyPlot& p) {
  v("kind", &p.kind), v("metric", yaml::Custom(&p.metrics, ReadOneMetric)), v("metrics", &p.metrics);
  v("x", &p.x), v("title", &p.title);
}

template <class V>
void Visit(V& v, StudySlurmConfig& s) {
  v("partition", &s.partition), v("time_per_point", &s.time_per_point), v("mem_per_point", &s.mem_per_point);
  v("cpus_per_point", &s.cpus_per_point), v("max_parallel", &s.max_parallel), v("sbatch_args", &s.sbatch_args);
  v("poll_interval_s", &s.poll_interval_s);
}

/// rank_by: a list of metric names, each checked where it stands.
static void ReadRankBy(const yaml::Section& at, const YAML::Node& n, std::vector<std::string>* rank_by) {
  if (!n.IsSequence()) throw yaml::ParseError(yaml::Where(at.file, n) + "rank_by: expected a list of metric names");
  std::vector<std::string> names;
  for (const YAML::Node& m : n) {
    yaml::ReadAs(at.file, m, at.path, &names.emplace_back());
    if (!FindStudyMetric(names.back()))
      throw yaml::ParseError(yaml::Where(at.file, m) + "rank_by: unknown metric '" + names.back() +
                             "' (docs/studies.md lists them)");
  }
  *rank_by = std::move(names);
}

/// slurm: the section's fields, then its Validate, so a bad value names the section's line.
static void ReadSlurm(const yaml::Section& at, const YAML::Node& n, StudySlurmConfig* slurm) {
  StudySlurmConfig s = *slurm;
  yaml::ReadValue(at, n, &s);
  std::string why;
  if (!s.Validate(&why)) throw yaml::ParseError(yaml::Where(at.file, n) + why);
  *slurm = std::move(s);
}

/// In this order: the base sim config, the study's duration over it, then the sweep's variants start from it.
template <class V>
void Visit(V& v, StudyConfig& c) {
  v("name", &c.name), v("sim", yaml::Custom(&c.base, ReadBaseSim)), v("duration_s", &c.base.duration_s);
  v("slam_config", yaml::Custom(&c.slam_config_path, ReadRelativePath));
  const auto read_sweep = [&c](const yaml::Section& at, const YAML::Node& n, StudySweep* sweep) {
    ParseSweep(at, n, c.base, sweep);
  };
  v("sweep", yaml::Custom(&c.sweep, read_sweep)), v("plots", yaml::Custom(&c.plots, ReadPlots));
  v("rank_by", yaml::Custom(&c.rank_by, ReadRankBy)), v("slurm", yaml::Custom(&c.slurm, ReadSlurm));
}

namespace {

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
      {"dynamic_share", "moving objects' seen voxels in the map [-]", {"/dynamic/share_of_seen"}},
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
  for (const std::string& m : rank_by)
    if (!FindStudyMetric(m)) return fail("rank_by: unknown metric '" + m + "' (docs/studies.md lists them)");
  if (!slurm.Validate(&why)) return fail(why);
  return true;
}

Status LoadStudyConfig(const std::string& path, StudyConfig* config) {
  StudyConfig c = *config;
  c.source_path = path;
  try {
    const YAML::Node root = yaml::LoadFile(path);
    if (!root.IsMap()) throw yaml::ParseError(yaml::Where(path, root) + "study: expected a mapping");
    yaml::Parse(yaml::Section(path, "", "study"), root, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {  // anything a field reader did not foresee: still a message
    return Status::Error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(path + ": " + why);
  *config = c;
  return Status::Ok();
}

}  // namespace rotolidar::bench
