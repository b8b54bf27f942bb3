// Problem stretches of a run (scan_health.hpp).
#include "bench/run/scan_health.hpp"

#include <cstdio>

#include <nlohmann/json.hpp>

namespace rotolidar::bench {
namespace {

/// Tangent axes [tx ty tz rx ry rz] whose weight in the degenerate directions exceeds 0.5 in any scan.
std::string UnobservedAxes(const std::vector<ScanReport>& scans, size_t first, size_t last) {
  static const char* const kAxes[6] = {"tx", "ty", "tz", "rx", "ry", "rz"};
  Vector6d w = Vector6d::Zero();
  for (size_t i = first; i <= last; ++i) w = w.cwiseMax(scans[i].degeneracy.axis_weight);
  std::string out;
  for (int a = 0; a < 6; ++a)
    if (w(a) > 0.5) out += (out.empty() ? "" : " ") + std::string(kAxes[a]);
  return "unobserved " + (out.empty() ? std::string("mixed directions") : out);
}

/// Appends the stretches of one problem kind.
void CollectStretches(const std::vector<ScanReport>& scans, ScanProblem problem, ScanHealth* h) {
  const auto has = [&](const ScanReport& r) {
    if (problem == ScanProblem::kDegenerate) return r.registration.attempted && r.degeneracy.degenerate;
    return r.registration.attempted && !r.registration.converged;
  };
  for (size_t i = 0; i < scans.size();) {
    if (!has(scans[i])) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j + 1 < scans.size() && has(scans[j + 1])) ++j;
    ScanProblemStretch s;
    s.problem = problem;
    s.first = i, s.last = j;
    s.t_start_s = scans[i].t_start_s, s.t_end_s = scans[j].t_end_s;
    s.reason = problem == ScanProblem::kDegenerate ? UnobservedAxes(scans, i, j) : scans[i].registration.message;
    if (s.reason.empty()) s.reason = "no reason reported";
    h->stretches.push_back(s);
    (problem == ScanProblem::kDegenerate ? h->degenerate : h->not_converged) += s.scans();
    i = j + 1;
  }
}

}  // namespace

const char* ScanProblemName(ScanProblem p) {
  return p == ScanProblem::kDegenerate ? "degenerate" : "registration failed";
}

ScanHealth AssessScanHealth(const std::vector<ScanReport>& scans) {
  ScanHealth h;
  h.scans = scans.size();
  CollectStretches(scans, ScanProblem::kNotConverged, &h);
  CollectStretches(scans, ScanProblem::kDegenerate, &h);
  std::stable_sort(h.stretches.begin(), h.stretches.end(),
                   [](const ScanProblemStretch& a, const ScanProblemStretch& b) { return a.first < b.first; });
  return h;
}

std::string FormatStretch(const ScanProblemStretch& s, Seconds t0_s) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "t %.2f-%.2f s (%zu scan%s): ", s.t_start_s - t0_s, s.t_end_s - t0_s, s.scans(),
                s.scans() == 1 ? "" : "s");
  return buf + std::string(ScanProblemName(s.problem)) + ": " + s.reason;
}

nlohmann::json ScanHealthJson(const ScanHealth& h) {
  nlohmann::json stretches = nlohmann::json::array();
  for (const ScanProblemStretch& s : h.stretches)
    stretches.push_back({{"problem", ScanProblemName(s.problem)}, {"t_start_s", s.t_start_s},
                         {"t_end_s", s.t_end_s}, {"scans", s.scans()}, {"reason", s.reason}});
  return {{"scans", h.scans}, {"not_converged", h.not_converged}, {"degenerate", h.degenerate},
          {"stretches", stretches}};
}

}  // namespace rotolidar::bench
