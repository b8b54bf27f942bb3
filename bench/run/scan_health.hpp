#pragma once
// What went wrong in a run, from its scan reports: scans whose scan-to-map registration did not converge, and
// scans whose registration was degenerate (a direction the LiDAR did not observe; the IMU held it). Consecutive
// scans with the same problem form one stretch, so a 3 s featureless corridor is one warning, not 30.
// `rotolidar slam` prints one warning line per stretch, metrics.json counts them ("health"), and report.html
// shades them in its plots over time.
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/pipeline/estimator.hpp"

namespace rotolidar::bench {

enum class ScanProblem { kNotConverged, kDegenerate };
const char* ScanProblemName(ScanProblem p);  ///< "registration failed", "degenerate"

/// Consecutive scans with the same problem (scan indices first..last, inclusive).
struct ScanProblemStretch {
  ScanProblem problem = ScanProblem::kNotConverged;
  size_t first = 0, last = 0;      ///< indices into the run's scans
  Seconds t_start_s = 0.0;         ///< first scan's start
  Seconds t_end_s = 0.0;           ///< last scan's end
  /// Why: the registration's message of the first scan (not converged), or the unobserved tangent axes over
  /// the stretch (degenerate: e.g. "tx rz", the axes whose weight exceeds 0.5 in any of its scans).
  std::string reason;
  size_t scans() const { return last - first + 1; }
};

struct ScanHealth {
  size_t scans = 0;
  size_t not_converged = 0;  ///< attempted registrations that did not converge
  size_t degenerate = 0;     ///< scans with a degenerate registration
  std::vector<ScanProblemStretch> stretches;  ///< in time order (a scan may be in one of each kind)
};

/// Scans that never attempted a registration (the first scan, a held static start) are not problems.
ScanHealth AssessScanHealth(const std::vector<ScanReport>& scans);

/// "t 12.30-13.10 s (8 scans): registration failed: <reason>", times relative to t0_s.
std::string FormatStretch(const ScanProblemStretch& s, Seconds t0_s);

/// {"scans", "not_converged", "degenerate", "stretches": [{"problem", "t_start_s", "t_end_s", "scans",
/// "reason"}]} with absolute times (the trajectory's clock).
nlohmann::json ScanHealthJson(const ScanHealth& health);

}  // namespace rotolidar::bench
