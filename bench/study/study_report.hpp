#pragma once
// A study's outputs from its results: the table (study.csv), the plots (plots/*.svg, bench/report/svg_plot.hpp)
// and a page that shows both (study.html). docs/studies.md describes the columns.
#include <string>
#include <vector>

#include "bench/study/study_runner.hpp"

namespace rotolidar::bench {

/// study.csv: a header, then one row per point in expansion order: point id, state (ran/resumed/failed), exit
/// code, the point's parameters (variant, scene, carrier, axis, profile, motor_speed_radps, seed, duration_s;
/// the values it ran with, swept or not), then every StudyMetrics() column. Missing values are empty fields.
std::string StudyCsv(const StudyResult& result);

/// One SVG per config.plots entry (DefaultStudyPlots when empty). Values of failed points are left out; points
/// that differ only in seed are averaged, with the standard deviation as error bars when there are several.
struct StudyFigure {
  std::string file_name;  ///< e.g. "01_coverage_total.svg"
  std::string title;
  std::string svg;
};
std::vector<StudyFigure> StudyFigures(const StudyConfig& config, const StudyResult& result);

/// study.html: title, counts, the figures inline, the table with links to each point's folder and log.
std::string StudyHtml(const StudyConfig& config, const StudyResult& result, const std::vector<StudyFigure>& figures);

/// Writes study.csv, plots/*.svg and study.html into out_dir (each by an atomic rename).
Status WriteStudyOutputs(const StudyConfig& config, const StudyResult& result, const std::string& out_dir);

}  // namespace rotolidar::bench
