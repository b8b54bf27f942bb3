// Per-point deskew error against truth (contract in deskew_error.hpp).
#include "bench/metrics/deskew_error.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "bench/eval/trajectory_lookup.hpp"
#include "sim/truth/truth.hpp"

namespace rotolidar::bench {

ErrorStats SummarizeErrors(std::vector<float> e) {
  ErrorStats s;
  s.count = e.size();
  if (e.empty()) return s;
  std::sort(e.begin(), e.end());
  double sum = 0.0, sq = 0.0;
  for (const float v : e) sum += v, sq += double(v) * v;
  const std::size_t n = e.size();
  auto rank = [&](double q) {  // nearest rank, 1-based ceil(q n)
    const std::size_t r = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
    return static_cast<double>(e[std::clamp<std::size_t>(r, 1, n) - 1]);
  };
  s.mean_m = sum / static_cast<double>(n);
  s.median_m = n % 2 ? e[n / 2] : 0.5 * (double(e[n / 2 - 1]) + double(e[n / 2]));
  s.p90_m = rank(0.90);
  s.p95_m = rank(0.95);
  s.rmse_m = std::sqrt(sq / static_cast<double>(n));
  s.max_m = e.back();
  return s;
}

Status LoadDeskewTruth(const std::string& recording_dir, DeskewTruth* truth) {
  DeskewTruth t;
  const std::pair<const char*, Trajectory*> files[] = {{"base.tum", &t.T_world_base}, {"lidar.tum", &t.T_world_lidar}};
  for (const auto& [name, trajectory] : files) {
    const std::string path = recording_dir + "/truth/" + name;
    if (Status s = sim::ReadTum(path, trajectory); !s) return s;
    if (trajectory->size() < 2) return Status::Error(path + ": the deskew error needs >= 2 truth poses");
  }
  *truth = std::move(t);
  return Status::Ok();
}

Status ScanDeskewError(const DeskewTruth& truth, const ScanReport& report, ScanDeskewErrors* out) {
  *out = ScanDeskewErrors();
  out->t_start_s = report.t_start_s;
  std::ostringstream where;
  where << "deskew error, scan at t = " << report.t_start_s << " s: ";
  if (report.deskew_source.size() != report.deskewed_base.size())
    return Status::Error(where.str() + std::to_string(report.deskew_source.size()) + " source points but " +
                         std::to_string(report.deskewed_base.size()) + " deskewed positions");
  if (report.deskew_source.empty() && report.num_points > 0)
    return Status::Error(where.str() + "no deskew data (run the estimator with keep_deskewed)");
  Pose3 T_world_base_start;
  if (!PoseAt(truth.T_world_base, report.t_start_s, &T_world_base_start)) {
    out->num_outside_truth = report.deskew_source.size();
    return Status::Ok();
  }
  const Pose3 T_base_start_world = T_world_base_start.inverse();
  out->errors_m.reserve(report.deskew_source.size());
  for (std::size_t i = 0; i < report.deskew_source.size(); ++i) {
    const LidarPoint& lp = report.deskew_source[i];
    const Eigen::Vector3f& est = report.deskewed_base[i];
    if (!est.allFinite()) {
      ++out->num_not_deskewed;
      continue;
    }
    Pose3 T_world_lidar;
    if (!PoseAt(truth.T_world_lidar, lp.t_s, &T_world_lidar)) {
      ++out->num_outside_truth;
      continue;
    }
    const Eigen::Vector3d p_true = T_base_start_world * (T_world_lidar * Eigen::Vector3d(lp.x_m, lp.y_m, lp.z_m));
    out->errors_m.push_back(static_cast<float>((est.cast<double>() - p_true).norm()));
  }
  return Status::Ok();
}

Status DeskewErrorAccumulator::Add(const ScanReport& report) {
  ScanDeskewErrors scan;
  if (Status s = ScanDeskewError(truth_, report, &scan); !s) return s;
  partial_.per_scan.push_back(SummarizeErrors(scan.errors_m));
  partial_.scan_t_start_s.push_back(report.t_start_s);
  partial_.num_not_deskewed += scan.num_not_deskewed;
  partial_.num_outside_truth += scan.num_outside_truth;
  all_m_.insert(all_m_.end(), scan.errors_m.begin(), scan.errors_m.end());
  return Status::Ok();
}

DeskewErrorResult DeskewErrorAccumulator::Result() const {
  DeskewErrorResult r = partial_;
  r.all = SummarizeErrors(all_m_);
  std::vector<float> medians;
  for (const ErrorStats& s : r.per_scan)
    if (s.count > 0) medians.push_back(static_cast<float>(s.median_m));
  r.scan_medians = SummarizeErrors(medians);
  return r;
}

Status EvaluateDeskew(const DeskewTruth& truth, const std::vector<ScanReport>& reports, DeskewErrorResult* result) {
  DeskewErrorAccumulator acc(truth);
  for (const ScanReport& r : reports)
    if (Status s = acc.Add(r); !s) return s;
  *result = acc.Result();
  return Status::Ok();
}

}  // namespace rotolidar::bench
