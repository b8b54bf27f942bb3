#pragma once
// Trade studies (`rotolidar study STUDY.yaml`, docs/studies.md): a base sim config, sweep axes (a list of values
// per parameter, expanded as a full factorial) and the plots to draw from the results table.
//
// YAML layout (every key optional except that at least one point must result; unknown keys are errors naming
// file:line):
//   name: fig9_rotation            # title of study.html
//   sim: {sim YAML keys} | path    # the base sim config: an inline mapping or a sim YAML file (relative to the
//                                  # study file), applied over sim::DefaultSimConfig() (sim/sim_config.hpp)
//   duration_s: 20                 # shortcut for sim.duration_s
//   slam_config: path              # estimator config YAML for every point (relative to the study file)
//   sweep:
//     variant: {NAME: {sim YAML keys}, ...}     # named overrides of the base config (e.g. fixed vs rotating)
//     motor_speed_radps: [1.3, 2.6, 5.2]        # motor.profile.speed_radps
//     profile: [constant, trapezoid, nodding]   # motor.profile.type
//     axis: [horizontal, vertical]              # rig_model.motor.axis
//     scene: [box_room, corridor]
//     carrier: [handheld, wheeled]              # carrier.type (without waypoints: the scene's default path)
//     seed: [1, 2, 3]
//   plots:                                      # default: see DefaultStudyPlots
//     - coverage_total                          # shorthand: a line plot of the metric against motor speed
//     - {kind: line, metric: ate_rmse_m, x: motor_speed_radps, title: ...}
//     - {kind: bars, metrics: [coverage_total, completeness_total], title: ...}
//   rank_by: [ate_rmse_m, coverage_total]       # study.html's ranking (study_ranking.hpp); [] = none
//   slurm: {partition: ..., time_per_point: ..., ...}  # the Slurm backend's sbatch options (study_slurm_config.hpp)
// A point applies, in order: the base config, its variant's keys, then the typed axes (speed, profile, axis,
// scene, carrier, seed). Axes left out keep the (variant's) config value and are not part of a point's name.
#include <cstdint>
#include <string>
#include <vector>

#include "bench/study/study_slurm_config.hpp"
#include "core/util/status.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::bench {

/// One value of the `variant` axis: a name and the base config with that variant's keys applied.
struct StudyVariant {
  std::string name;  ///< [A-Za-z0-9_.-]+, unique within the study
  sim::SimConfig sim;
};

/// The sweep axes. An empty list = the axis is not swept (every point keeps the config's value).
struct StudySweep {
  std::vector<StudyVariant> variants;
  std::vector<double> motor_speed_radps;  ///< |w| <= 200 rad/s (MotorProfileConfig's limit)
  std::vector<sim::MotorProfileType> profiles;
  std::vector<sim::MotorAxis> axes;
  std::vector<std::string> scenes;  ///< scene names or scene file paths (sim::ResolveScenePath)
  std::vector<sim::CarrierType> carriers;
  std::vector<uint64_t> seeds;
  /// Number of points of the full factorial (the product of the non-empty list sizes; 1 when none is swept).
  size_t NumPoints() const;
};

enum class StudyPlotKind {
  kLine,  ///< one metric against a swept numeric parameter; one line per combination of the other axes
  kBars,  ///< grouped bars: one category per combination of the swept axes (seeds averaged), one bar per metric
};

struct StudyPlot {
  StudyPlotKind kind = StudyPlotKind::kLine;
  std::vector<std::string> metrics;     ///< StudyMetrics() names; exactly one for a line plot
  std::string x = "motor_speed_radps";  ///< line plots: "motor_speed_radps" or "seed" (must be swept)
  std::string title;                    ///< empty = from the metrics
};

struct StudyConfig {
  std::string name = "study";
  std::string source_path;  ///< the study file (for messages); "" when built in code
  sim::SimConfig base = sim::PresetSimConfig(sim::Realism::kTypical);  ///< studies run `typical` unless told
  std::string slam_config_path;  ///< "" = the estimator's defaults; else an absolute or CWD-relative path
  StudySweep sweep;
  std::vector<StudyPlot> plots;  ///< empty = DefaultStudyPlots(sweep)
  StudySlurmConfig slurm;        ///< used by `--backend slurm` only
  /// The metrics study.html ranks the configurations by (bench/study/study_ranking.hpp); empty = no ranking.
  std::vector<std::string> rank_by = {"ate_rmse_m", "coverage_total"};

  /// False with a message naming the field: an invalid base or variant config, a bad speed, duplicate or
  /// malformed variant names, unknown plot metrics, a line plot whose x is not swept, more than 10000 points,
  /// an invalid slurm section (StudySlurmConfig::Validate).
  bool Validate(std::string* error) const;
};

/// A result column of study.csv: its name, what it is, and where demo's metrics.json holds it.
struct StudyMetric {
  std::string name;          ///< column name, e.g. "ate_rmse_m"
  std::string label;         ///< axis label with unit, e.g. "ATE RMSE [m]"
  /// RFC 6901 pointers into metrics.json, the first present one wins (a key whose writer is still settling may
  /// list its candidate spellings); empty = measured by the study itself (runtime_s).
  std::vector<std::string> json_pointers;
};
/// Every metric the study table carries, in column order (docs/studies.md lists them).
const std::vector<StudyMetric>& StudyMetrics();
/// The metric named `name`, or nullptr.
const StudyMetric* FindStudyMetric(const std::string& name);

/// Line plots of ATE, coverage, deskew error and runtime against motor speed when the speed is swept, else the
/// same metrics as bar charts over the points.
std::vector<StudyPlot> DefaultStudyPlots(const StudySweep& sweep);

/// Reads a study file over *config's values (see the layout above); relative paths in it (sim, slam_config)
/// resolve against the file's folder. Errors name file:line and the key; *config is untouched on error.
Status LoadStudyConfig(const std::string& path, StudyConfig* config);

}  // namespace rotolidar::bench
