#include "core/preprocess/filters.hpp"
#include "core/preprocess/ring_sor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>


#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/search/kdtree.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/util/log.hpp"
#include "core/util/voxel_hash.hpp"

namespace rotolidar {
namespace {

using namespace ring_sor;

/// Keeps the points whose `keep` flag is set, in order; returns how many went.
std::size_t Compact(const std::vector<uint8_t>& keep, std::vector<ScanPoint>* points) {
  std::size_t out = 0;
  for (std::size_t i = 0; i < points->size(); ++i) {
    if (keep[i]) (*points)[out++] = (*points)[i];
  }
  const std::size_t removed = points->size() - out;
  points->resize(out);
  return removed;
}

/// floor(v) as an integer, for finite |v| < 2^62 (std::floor is a library call without SSE4.1).
inline int64_t FloorToInt(double v) {
  const int64_t i = static_cast<int64_t>(v);  // truncates toward zero
  return i - (static_cast<double>(i) > v ? 1 : 0);
}

bool IsFinite(const ScanPoint& p) { return p.p_base.allFinite() && std::isfinite(p.range_m); }

// PCL's own filter: the seed's rule as written.
std::vector<uint8_t> PclSorKeep(const pcl::PointCloud<pcl::PointXYZ>::Ptr& cloud, int k, double std_mul) {
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
  sor.setInputCloud(cloud);
  sor.setMeanK(k);
  sor.setStddevMulThresh(std_mul);
  pcl::Indices kept;
  sor.filter(kept);
  std::vector<uint8_t> keep(cloud->size(), 0);
  for (const auto i : kept) keep[static_cast<std::size_t>(i)] = 1;
  return keep;
}

// The same statistics as PCL's filter (K-NN search excluding the query, sample variance), on d_i / range_i.
std::vector<uint8_t> RangeNormalizedSorKeep(const pcl::PointCloud<pcl::PointXYZ>::Ptr& cloud,
                                            const std::vector<ScanPoint>& points, int k, double std_mul) {
  pcl::search::KdTree<pcl::PointXYZ> tree(false);
  tree.setInputCloud(cloud);
  pcl::Indices nn(k + 1);
  std::vector<float> nn_sq(k + 1);
  std::vector<double> stat(points.size(), 0.0);
  double sum = 0.0, sq_sum = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!(points[i].range_m > 0.f)) continue;  // no statistic: removed below, outside mu and sigma
    const int found = tree.nearestKSearch(static_cast<pcl::index_t>(i), k + 1, nn, nn_sq);
    double dist_sum = 0.0;  // over all k + 1 results: the query itself adds 0 wherever the search ranks it
    for (int j = 0; j < found; ++j) dist_sum += std::sqrt(double(nn_sq[j]));
    stat[i] = dist_sum / k / points[i].range_m;
    sum += stat[i], sq_sum += stat[i] * stat[i];
  }
  const double n = static_cast<double>(std::count_if(points.begin(), points.end(),
                                                      [](const ScanPoint& p) { return p.range_m > 0.f; }));
  const double mean = sum / n, stddev = std::sqrt(std::max(0.0, (sq_sum - sum * sum / n) / (n - 1.0)));
  std::vector<uint8_t> keep(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)  // fewer than 2 valid points: no spread, keep the valid ones
    keep[i] = points[i].range_m > 0.f && (n < 2.0 || stat[i] <= mean + std_mul * stddev);
  return keep;
}

/// PCL's rule on per-point statistics (NaN = none: kept, outside mu and sigma): removes stat > mu + std_mul * sigma
/// (sample sigma). Fewer than 2 statistics: no spread, everything kept.
std::vector<uint8_t> KeepBelowThreshold(const std::vector<double>& stat, double std_mul) {
  double sum = 0.0, sq_sum = 0.0, n = 0.0;
  for (const double s : stat)
    if (!std::isnan(s)) sum += s, sq_sum += s * s, n += 1.0;
  std::vector<uint8_t> keep(stat.size(), 1);
  if (n < 2.0) return keep;
  const double mean = sum / n, stddev = std::sqrt(std::max(0.0, (sq_sum - sum * sum / n) / (n - 1.0)));
  for (std::size_t i = 0; i < stat.size(); ++i) keep[i] = !(stat[i] > mean + std_mul * stddev);
  return keep;
}

}  // namespace

bool PreprocessConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& field, const std::string& rule, double got) {
    if (error) {
      std::ostringstream os;
      os << "preprocess." << field << " must be " << rule << " (got " << got << ")";
      *error = os.str();
    }
    return false;
  };
  if (!(min_range_m >= 0.0)) return fail("min_range_m", ">= 0", min_range_m);
  if (!(max_range_m > min_range_m) || !std::isfinite(max_range_m))
    return fail("max_range_m", "finite and > min_range_m", max_range_m);
  if (sor_k < 1) return fail("sor_k", ">= 1", sor_k);
  if (sor_ring_neighbours && sor_k > kMaxRingSorK)
    return fail("sor_k", "<= " + std::to_string(kMaxRingSorK) + " with sor_ring_neighbours", sor_k);
  if (!(sor_std_mul > 0.0) || !std::isfinite(sor_std_mul)) return fail("sor_std_mul", "finite and > 0", sor_std_mul);
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m)) return fail("voxel_m", "finite and > 0", voxel_m);
  const SorNeighbourhood& h = sor_neighbourhood;
  if (h.ring_window < 0) return fail("sor_neighbourhood.ring_window", ">= 0", h.ring_window);
  if (h.adjacent_rings < 0) return fail("sor_neighbourhood.adjacent_rings", ">= 0", h.adjacent_rings);
  if (h.adjacent_window < 0) return fail("sor_neighbourhood.adjacent_window", ">= 0", h.adjacent_window);
  if (h.ring_window == 0 && h.adjacent_rings == 0)
    return fail("sor_neighbourhood.ring_window", "> 0 when adjacent_rings is 0", h.ring_window);
  return true;
}

PreprocessResult Preprocess(const std::vector<ScanPoint>& points, const PreprocessConfig& config) {
  return Preprocess(std::vector<ScanPoint>(points), config);
}

// The non-finite and range stages in one compaction pass (a point counts for the first stage that removes it).
PreprocessResult Preprocess(std::vector<ScanPoint>&& points, const PreprocessConfig& config) {
  std::string why;
  ROTOLIDAR_CHECK(config.Validate(&why), why);
  PreprocessResult result;
  result.num_input = points.size();
  result.points = std::move(points);
  std::vector<ScanPoint>& pts = result.points;
  std::size_t out = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const ScanPoint& p = pts[i];
    if (!IsFinite(p)) {
      ++result.removed_nonfinite;
    } else if (config.enable_range && !(p.range_m >= config.min_range_m && p.range_m <= config.max_range_m)) {
      ++result.removed_range;
    } else {
      if (out != i) pts[out] = p;
      ++out;
    }
  }
  pts.resize(out);
  if (config.enable_sor && config.sor_ring_neighbours)
    result.removed_sor = RingStatisticalOutlierFilter(config.sor_k, config.sor_std_mul, config.sor_range_normalized,
                                                      config.sor_neighbourhood, &pts);
  else if (config.enable_sor)
    result.removed_sor = StatisticalOutlierFilter(config.sor_k, config.sor_std_mul, config.sor_range_normalized, &pts);
  if (config.enable_voxel) result.removed_voxel = VoxelFilter(config.voxel_m, &pts);
  return result;
}

std::size_t RemoveNonFinite(std::vector<ScanPoint>* points) {
  std::vector<uint8_t> keep(points->size());
  for (std::size_t i = 0; i < points->size(); ++i) keep[i] = IsFinite((*points)[i]);
  return Compact(keep, points);
}

std::size_t RangeFilter(double min_range_m, double max_range_m, std::vector<ScanPoint>* points) {
  std::vector<uint8_t> keep(points->size());
  for (std::size_t i = 0; i < points->size(); ++i) {
    const double r = (*points)[i].range_m;
    keep[i] = r >= min_range_m && r <= max_range_m;
  }
  return Compact(keep, points);
}

// Seed Eq. 1-2 on PCL's kd-tree (and, un-normalised, PCL's StatisticalOutlierRemoval itself).
std::size_t StatisticalOutlierFilter(int k, double std_mul, bool range_normalized, std::vector<ScanPoint>* points) {
  ROTOLIDAR_CHECK(k >= 1, "k = " << k);
  if (points->size() <= static_cast<std::size_t>(k)) return 0;  // no point has K neighbours: no statistic
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(points->size());
  for (const ScanPoint& p : *points) cloud->push_back(pcl::PointXYZ(p.p_base.x(), p.p_base.y(), p.p_base.z()));
  const std::vector<uint8_t> keep =
      range_normalized ? RangeNormalizedSorKeep(cloud, *points, k, std_mul) : PclSorKeep(cloud, k, std_mul);
  return Compact(keep, points);
}

std::vector<float> RingNeighbourMeanDistances(const std::vector<ScanPoint>& points, int k, const SorNeighbourhood& hood,
                                              bool vectorised) {
  ROTOLIDAR_CHECK(k >= 1 && k <= kMaxRingSorK, "k = " << k);
  ROTOLIDAR_CHECK(hood.ring_window >= 0 && hood.adjacent_rings >= 0 && hood.adjacent_window >= 0,
                  "negative SOR neighbourhood");
  return k <= 8    ? RingNeighbourDistances<8>(points, k, hood, vectorised)
         : k <= 16 ? RingNeighbourDistances<16>(points, k, hood, vectorised)
                   : RingNeighbourDistances<kMaxRingSorK>(points, k, hood, vectorised);
}

std::size_t RingStatisticalOutlierFilter(int k, double std_mul, bool range_normalized, const SorNeighbourhood& hood,
                                         std::vector<ScanPoint>* points) {
  const std::vector<float> mean_dist = RingNeighbourMeanDistances(*points, k, hood);
  std::vector<double> stat(points->size());  // NaN: no statistic (kept) or a bad range (removed below)
  for (std::size_t i = 0; i < points->size(); ++i) {
    const float r = (*points)[i].range_m;
    stat[i] = range_normalized && !(r > 0.f) ? std::nan("")
                                            : double(mean_dist[i]) / (range_normalized ? double(r) : 1.0);
  }
  std::vector<uint8_t> keep = KeepBelowThreshold(stat, std_mul);
  if (range_normalized)
    for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = keep[i] && (*points)[i].range_m > 0.f;
  return Compact(keep, points);
}

// A hash table on 64-bit integer voxel coordinates instead of pcl::VoxelGrid: VoxelGrid numbers voxels with a
// 32-bit index over the cloud's bounding box and, when that overflows (e.g. a rotating rig's 60 m-range scan, a
// 120 m cube, at 0.05 m: 1.4e10 voxels), logs a warning and returns the input unfiltered; and it outputs centroids,
// which carry no ring or firing time. Linear time (a sort of the keys cost 3x more per scan). The open-addressing
// table holds 32-bit voxel numbers and grows with the voxel count (load <= 1/2), not with the point count.
// Ring order keeps neighbours together, so the points are taken as runs of consecutive finite points in one voxel:
// one lookup per run, the voxel's sum carried in registers along it (still added point by point in index order, so
// the sums are those of the per-point loop and of VoxelFilter's std::map reference test), and the nearest-to-centroid
// pass walks the same runs.
namespace {

struct RepVoxel {
  int64_t key[3];
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();  ///< summed in index order
  std::size_t count = 0, best = 0;
  double best_sq = std::numeric_limits<double>::infinity();
};

/// Points [begin, end) of one voxel, consecutive in the input.
struct VoxelRun {
  uint32_t begin, end;
  int32_t voxel;
};

/// The voxel table: voxel numbers in creation order, found by key through open addressing.
class RepVoxelTable {
 public:
  explicit RepVoxelTable(std::size_t expected) {
    std::size_t slots = 64;
    while (slots < 2 * expected) slots *= 2;  // presized: rehashing only when the guess was low
    table_.assign(slots, -1);
    voxels.reserve(expected);
  }
  /// The voxel number of `key`, created (sums zero) when new.
  int32_t FindOrAdd(const int64_t* key) {
    std::size_t slot = SlotOf(key);
    if (table_[slot] >= 0) return table_[slot];
    if (2 * (voxels.size() + 1) > table_.size()) {  // grow and rehash, then find the new key's slot again
      table_.assign(2 * table_.size(), -1);
      for (std::size_t v = 0; v < voxels.size(); ++v) table_[SlotOf(voxels[v].key)] = static_cast<int32_t>(v);
      slot = SlotOf(key);
    }
    table_[slot] = static_cast<int32_t>(voxels.size());
    voxels.push_back(RepVoxel{{key[0], key[1], key[2]}});
    return table_[slot];
  }
  std::vector<RepVoxel> voxels;

 private:
  std::size_t SlotOf(const int64_t* key) const {  // the key's slot: its voxel's, or the empty one ending the probe
    const std::size_t mask = table_.size() - 1;
    std::size_t slot = VoxelHash(key[0], key[1], key[2]) & mask;
    for (int32_t v; (v = table_[slot]) >= 0; slot = (slot + 1) & mask) {
      const int64_t* o = voxels[v].key;
      if (o[0] == key[0] && o[1] == key[1] && o[2] == key[2]) break;
    }
    return slot;
  }
  std::vector<int32_t> table_;  ///< slot -> voxel number, -1 empty; size a power of two
};

/// Bounds [lo, hi) of the scaled coordinates d whose FloorToInt(d) is the key k: lo = k, hi = k + 1, exact below
/// 2^52; beyond that hi = lo, an empty range (such a point only starts runs of one, found through the table).
struct KeyRange {
  double lo[3], hi[3];
  explicit KeyRange(const int64_t* key) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = static_cast<double>(key[a]);
      hi[a] = std::abs(lo[a]) < 0x1p52 ? lo[a] + 1.0 : lo[a];
    }
  }
  /// FloorToInt(d) == key on every axis; false for non-finite d (NaN and +-inf fail a bound).
  bool Holds(double dx, double dy, double dz) const {
    return lo[0] <= dx && dx < hi[0] && lo[1] <= dy && dy < hi[1] && lo[2] <= dz && dz < hi[2];
  }
};

/// Splits the finite points into runs of one voxel and adds each point to its voxel's sum (index order).
std::vector<VoxelRun> AccumulateRuns(const std::vector<Eigen::Vector3f>& positions, double inv, RepVoxelTable* table) {
  std::vector<VoxelRun> runs;
  const std::size_t n = positions.size();
  for (std::size_t i = 0; i < n;) {
    const Eigen::Vector3f& p = positions[i];
    if (!p.allFinite()) {
      ++i;
      continue;
    }
    const int64_t key[3] = {FloorToInt(p.x() * inv), FloorToInt(p.y() * inv), FloorToInt(p.z() * inv)};
    const KeyRange range(key);
    const int32_t v = table->FindOrAdd(key);
    RepVoxel& voxel = table->voxels[v];
    Eigen::Vector3d sum = voxel.sum + p.cast<double>();
    std::size_t end = i + 1;
    for (; end < n; ++end) {  // the run goes on while the next point is in the same voxel (hence finite)
      const Eigen::Vector3f& q = positions[end];
      if (!range.Holds(q.x() * inv, q.y() * inv, q.z() * inv)) break;
      sum += q.cast<double>();
    }
    voxel.sum = sum;
    voxel.count += end - i;
    runs.push_back(VoxelRun{static_cast<uint32_t>(i), static_cast<uint32_t>(end), v});
    i = end;
  }
  return runs;
}

}  // namespace

std::vector<std::size_t> VoxelRepresentatives(const std::vector<Eigen::Vector3f>& positions, double voxel_m) {
  ROTOLIDAR_CHECK(voxel_m > 0.0 && std::isfinite(voxel_m), "voxel_m = " << voxel_m);
  ROTOLIDAR_CHECK(positions.size() < (std::size_t(1) << 31), "VoxelRepresentatives: too many points");
  RepVoxelTable table(positions.size() / 8 + 16);  // a scan's less-flat set: ~10 points per 0.2 m voxel
  const std::vector<VoxelRun> runs = AccumulateRuns(positions, 1.0 / voxel_m, &table);
  std::vector<RepVoxel>& voxels = table.voxels;
  for (RepVoxel& v : voxels) v.sum /= static_cast<double>(v.count);  // the centroid, in place of the sum
  for (const VoxelRun& run : runs) {  // nearest to the centroid, ties to the lower index (runs in index order)
    RepVoxel& v = voxels[run.voxel];
    double best_sq = v.best_sq;
    std::size_t best = v.best;
    for (uint32_t i = run.begin; i < run.end; ++i) {  // select, not branch: which point wins is random
      const double sq = (positions[i].cast<double>() - v.sum).squaredNorm();
      const bool better = sq < best_sq;
      best_sq = better ? sq : best_sq;
      best = better ? i : best;
    }
    v.best_sq = best_sq, v.best = best;
  }
  std::vector<uint8_t> is_best(positions.size(), 0);  // a flag scan keeps the indices ascending (no sort)
  for (const RepVoxel& v : voxels) is_best[v.best] = 1;
  std::vector<std::size_t> kept;
  kept.reserve(voxels.size());
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (is_best[i]) kept.push_back(i);
  return kept;
}

std::size_t VoxelFilter(double voxel_m, std::vector<ScanPoint>* points) {
  std::vector<Eigen::Vector3f> positions(points->size());
  for (std::size_t i = 0; i < points->size(); ++i) positions[i] = (*points)[i].p_base;
  std::vector<uint8_t> keep(points->size(), 0);
  for (const std::size_t i : VoxelRepresentatives(positions, voxel_m)) keep[i] = 1;
  return Compact(keep, points);
}

}  // namespace rotolidar
