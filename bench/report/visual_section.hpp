#pragma once
// Internal to bench/report: the run report's "camera" section (a run with visual.enabled): the camera path's
// per-scan statistics over time (scans.csv vis_* columns) and the tracked features drawn on sample frames.
#include "bench/report/html_report.hpp"
#include "bench/report/run_report.hpp"

namespace rotolidar::bench::report {

/// Adds the section when some scan used a camera frame; the sample frames need in.recording_dir's camera
/// frames (re-tracked with the default tracker settings over the half second before each sample time).
void AddVisualSection(const RunReportInput& in, HtmlReport* html);

}  // namespace rotolidar::bench::report
