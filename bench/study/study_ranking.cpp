#include "bench/study/study_ranking.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "bench/study/study_seeds.hpp"

namespace rotolidar::bench {
namespace {

bool IsCondition(const std::string& axis) { return axis == "scene" || axis == "carrier"; }

/// "axis=value, ..." of the swept axes that are (condition) or are not (design) scene/carrier; seed left out.
std::string Label(const StudyPoint& p, bool condition, const char* none) {
  std::string label;
  for (const auto& [axis, value] : p.swept)
    if (axis != "seed" && IsCondition(axis) == condition) label += (label.empty() ? "" : ", ") + axis + "=" + value;
  return label.empty() ? none : label;
}

MetricSpread Spread(const std::vector<double>& v) {
  MetricSpread s;
  s.n = v.size();
  if (v.empty()) return s.mean = s.sd = s.min = s.max = kStudyNaN, s;
  double sum = 0, sq = 0;
  for (double x : v) sum += x;
  s.mean = sum / v.size();
  for (double x : v) sq += (x - s.mean) * (x - s.mean);
  s.sd = v.size() > 1 ? std::sqrt(sq / (v.size() - 1)) : 0.0;
  s.min = *std::min_element(v.begin(), v.end()), s.max = *std::max_element(v.begin(), v.end());
  return s;
}

double WelchT(const MetricSpread& a, const MetricSpread& b) {
  if (a.n < 2 || b.n < 2) return kStudyNaN;
  const double se2 = a.sd * a.sd / a.n + b.sd * b.sd / b.n;
  return se2 > 0 ? (a.mean - b.mean) / std::sqrt(se2) : kStudyNaN;
}

/// a before b on one metric: a valid mean first, then the better one.
bool Better(const MetricSpread& a, const MetricSpread& b, bool higher) {
  if (std::isfinite(a.mean) != std::isfinite(b.mean)) return std::isfinite(a.mean);
  return higher ? a.mean > b.mean : a.mean < b.mean;
}

/// Ranks the groups of one partition in place (scores, then order, rank and t against the best).
void RankPartition(std::vector<RankedGroup>* part, const std::vector<std::string>& rank_by) {
  for (size_t m = 0; m < rank_by.size(); ++m) {
    const bool higher = HigherIsBetter(rank_by[m]);
    for (RankedGroup& g : *part) {  // rank = 1 + the number of strictly better groups (ties share a rank)
      int better = 0;
      for (const RankedGroup& o : *part) better += Better(o.metrics[m], g.metrics[m], higher);
      g.score += 1 + better;
    }
  }
  const bool higher0 = HigherIsBetter(rank_by[0]);
  std::stable_sort(part->begin(), part->end(), [higher0](const RankedGroup& a, const RankedGroup& b) {
    if ((a.failed > 0) != (b.failed > 0)) return b.failed > 0;
    if (a.score != b.score) return a.score < b.score;
    return Better(a.metrics[0], b.metrics[0], higher0);
  });
  for (size_t i = 0; i < part->size(); ++i) {
    (*part)[i].rank = int(i) + 1;
    (*part)[i].t_vs_best = i == 0 ? 0.0 : WelchT((*part)[i].metrics[0], part->front().metrics[0]);
  }
}

}  // namespace

bool HigherIsBetter(const std::string& metric) {
  return metric.rfind("coverage_", 0) == 0 || metric.rfind("completeness_", 0) == 0 || metric == "map_points" ||
         metric == "slam_realtime_factor";
}

std::vector<RankedGroup> RankStudyGroups(const StudyResult& result, const std::vector<std::string>& rank_by) {
  if (rank_by.empty()) return {};
  std::vector<size_t> columns;
  for (const std::string& name : rank_by)
    for (size_t i = 0; i < StudyMetrics().size(); ++i)
      if (StudyMetrics()[i].name == name) columns.push_back(i);
  if (columns.size() != rank_by.size()) return {};  // an unknown metric: Validate rejects it before
  std::vector<RankedGroup> groups;
  std::vector<std::vector<std::vector<double>>> values;  // group -> metric -> finite values over seeds
  std::map<std::string, size_t> index;
  for (const StudyPointResult& r : result.points) {
    const std::string key = GroupWithoutSeed(r.point);
    if (!index.count(key)) {
      index[key] = groups.size();
      RankedGroup g;
      g.partition = Label(r.point, true, "all points"), g.design = Label(r.point, false, "base"), g.group = key;
      groups.push_back(std::move(g));
      values.emplace_back(columns.size());
    }
    const size_t g = index[key];
    ++groups[g].seeds;
    if (r.state == PointState::kFailed) {
      ++groups[g].failed;
      continue;
    }
    for (size_t m = 0; m < columns.size(); ++m)
      if (std::isfinite(r.metrics[columns[m]])) values[g][m].push_back(r.metrics[columns[m]]);
  }
  std::vector<std::string> partitions;
  std::map<std::string, std::vector<RankedGroup>> parts;
  for (size_t g = 0; g < groups.size(); ++g) {
    for (const std::vector<double>& v : values[g]) groups[g].metrics.push_back(Spread(v));
    if (!parts.count(groups[g].partition)) partitions.push_back(groups[g].partition);
    parts[groups[g].partition].push_back(groups[g]);
  }
  std::vector<RankedGroup> out;
  for (const std::string& p : partitions) {
    RankPartition(&parts[p], rank_by);
    out.insert(out.end(), parts[p].begin(), parts[p].end());
  }
  return out;
}

}  // namespace rotolidar::bench
