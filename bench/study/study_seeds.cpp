// Statistics over seeds (study_seeds.hpp).
#include "bench/study/study_seeds.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

namespace rotolidar::bench {

double NearestRankPercentile(std::vector<double> values, double q) {
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
               values.end());
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const size_t rank = std::max<size_t>(1, size_t(std::ceil(q * double(values.size()) - 1e-9)));
  return values[std::min(rank, values.size()) - 1];
}

std::string GroupWithoutSeed(const StudyPoint& point) {
  std::string id;
  for (const auto& [axis, value] : point.swept) {
    if (axis == "seed") continue;
    if (!id.empty()) id += "__";
    id += axis + "-" + value;
  }
  return id.empty() ? "base" : id;
}

std::vector<SeedStatistics> StudySeedStatistics(const StudyResult& result) {
  std::vector<std::string> order;
  std::map<std::string, std::vector<const StudyPointResult*>> groups;
  for (const StudyPointResult& r : result.points) {
    const std::string g = GroupWithoutSeed(r.point);
    if (!groups.count(g)) order.push_back(g);
    groups[g].push_back(&r);
  }
  std::vector<SeedStatistics> out;
  const std::vector<StudyMetric>& metrics = StudyMetrics();
  for (const std::string& g : order) {
    for (size_t m = 0; m < metrics.size(); ++m) {
      SeedStatistics s;
      s.group = g;
      s.metric = metrics[m].name;
      std::vector<double> v;
      for (const StudyPointResult* r : groups[g]) {
        ++s.seeds;
        if (r->state == PointState::kFailed) {
          ++s.failed;
          continue;
        }
        if (m < r->metrics.size() && std::isfinite(r->metrics[m])) v.push_back(r->metrics[m]);
      }
      s.values = v.size();
      if (!v.empty()) {
        s.median = NearestRankPercentile(v, 0.5);
        s.p90 = NearestRankPercentile(v, 0.9);
        s.min = *std::min_element(v.begin(), v.end());
        s.max = *std::max_element(v.begin(), v.end());
      }
      out.push_back(s);
    }
  }
  return out;
}

std::string StudySeedsCsv(const std::vector<SeedStatistics>& stats) {
  std::ostringstream os;
  os.precision(10);
  os << "group,metric,seeds,failed,values,median,p90,min,max\n";
  for (const SeedStatistics& s : stats) {
    os << '"' << s.group << "\"," << s.metric << ',' << s.seeds << ',' << s.failed << ',' << s.values;
    if (s.values > 0) os << ',' << s.median << ',' << s.p90 << ',' << s.min << ',' << s.max << '\n';
    else os << ",,,,\n";
  }
  return os.str();
}

}  // namespace rotolidar::bench
