#pragma once
// Internal to bench/report: one function per section of the run report (run_report.hpp lists the sections).
// Each adds its section to `html` or, when its data is missing, nothing (RenderRunReport writes the notes).
#include "bench/report/html_report.hpp"
#include "bench/report/run_report.hpp"

namespace rotolidar::bench::report {

void AddTrajectorySection(const RunReportInput& in, HtmlReport* html);
void AddApeSection(const RunReportInput& in, HtmlReport* html);
void AddRpeSection(const RunReportInput& in, HtmlReport* html);
void AddHealthSection(const RunReportInput& in, HtmlReport* html);
void AddTimingSection(const RunReportInput& in, HtmlReport* html);
void AddMapSection(const RunReportInput& in, HtmlReport* html);
void AddCoverageSection(const RunReportInput& in, HtmlReport* html);
void AddElementsSection(const RunReportInput& in, HtmlReport* html);

/// Per-stage wall times over the scans [ms]: median, mean, p95, max for each ScanTimings member.
struct StageTiming {
  std::string stage;
  double median_ms = 0.0, mean_ms = 0.0, p95_ms = 0.0, max_ms = 0.0;
};
/// Empty when there are no scans or every stage time is zero (an estimator without stage timings).
std::vector<StageTiming> ComputeStageTimings(const std::vector<ScanReport>& scans);

}  // namespace rotolidar::bench::report
