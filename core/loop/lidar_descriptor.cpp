#include "core/loop/lidar_descriptor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_set>
#include <utility>

#include "core/util/validation.hpp"

namespace rotolidar::loop {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

/// Accumulates points into the polar grid; Finish() turns the per-cell state into cell values and keys.
class GridBuilder {
 public:
  explicit GridBuilder(const LidarDescriptorConfig& c)
      : c_(c),
        ring_scale_(c.num_rings / c.max_radius_m),
        sector_scale_(c.num_sectors / kTwoPi),
        band_scale_(c.num_height_bands / (c.max_z_m - c.min_z_m)),
        max_height_(Eigen::MatrixXf::Zero(c.num_rings, c.num_sectors)),
        bands_(size_t(c.num_rings) * size_t(c.num_sectors), 0u) {}

  void Add(float x, float y, float z) {
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) return;
    if (z < c_.min_z_m || z > c_.max_z_m) return;
    const double range_m = std::hypot(double(x), double(y));
    const int ring = int(range_m * ring_scale_);
    if (ring >= c_.num_rings) return;
    // Sector boundaries at -pi + j w, so a yaw of k whole sectors shifts every point by exactly k columns.
    int sector = int((std::atan2(double(y), double(x)) + M_PI) * sector_scale_);
    if (sector >= c_.num_sectors) sector = c_.num_sectors - 1;  // azimuth == pi
    const double height_m = double(z) - c_.min_z_m;
    float& h = max_height_(ring, sector);
    // A floor of 1 mm keeps a point exactly at min_z_m from reading as an empty cell.
    h = std::max(h, float(std::max(height_m, 1e-3)));
    const int band = std::min(int(height_m * band_scale_), c_.num_height_bands - 1);
    bands_[size_t(sector) * size_t(c_.num_rings) + size_t(ring)] |= (1u << band);
    ++num_points_;
  }

  LidarDescriptor Finish() const {
    LidarDescriptor d;
    d.num_points = num_points_;
    if (c_.cell_value == LidarDescriptorConfig::CellValue::kMaxHeight) {
      d.cells = max_height_;
    } else {
      d.cells.resize(c_.num_rings, c_.num_sectors);
      for (int s = 0; s < c_.num_sectors; ++s)
        for (int r = 0; r < c_.num_rings; ++r)
          d.cells(r, s) = float(__builtin_popcount(bands_[size_t(s) * size_t(c_.num_rings) + size_t(r)])) /
                          float(c_.num_height_bands);
    }
    // The paper's ring key: the share of occupied cells of each ring (an integer count: exactly yaw-invariant). It
    // ranked true revisits better than the rings' mean cell value in the tests (street and hall).
    d.ring_key = (d.cells.array() > 0.0f).cast<float>().rowwise().sum() / float(c_.num_sectors);
    d.sector_key = d.cells.cast<double>().colwise().mean().transpose().cast<float>();
    return d;
  }

 private:
  const LidarDescriptorConfig& c_;
  const double ring_scale_, sector_scale_, band_scale_;
  Eigen::MatrixXf max_height_;
  std::vector<uint32_t> bands_;  ///< occupied-band bit masks, column-major like the matrix
  size_t num_points_ = 0;
};

/// Scan Context distance for one cyclic shift; column norms precomputed.
double ShiftedDistance(const LidarDescriptor& a, const LidarDescriptor& b, const Eigen::VectorXf& norm_a,
                       const Eigen::VectorXf& norm_b, int shift) {
  const int n = a.num_sectors();
  double sum = 0.0;
  int count = 0;
  for (int j = 0; j < n; ++j) {
    const int k = (j + shift) % n;
    const bool empty_a = norm_a[j] == 0.0f, empty_b = norm_b[k] == 0.0f;
    if (empty_a && empty_b) continue;
    ++count;
    if (empty_a || empty_b) {
      sum += 1.0;
      continue;
    }
    sum += 1.0 - double(a.cells.col(j).dot(b.cells.col(k))) / (double(norm_a[j]) * double(norm_b[k]));
  }
  return count == 0 ? 1.0 : sum / count;
}

/// The shift that best aligns the sector keys (L2): the paper's coarse alignment.
int CoarseShift(const LidarDescriptor& a, const LidarDescriptor& b) {
  const int n = a.num_sectors();
  int best = 0;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int s = 0; s < n; ++s) {
    double cost = 0.0;
    for (int j = 0; j < n; ++j) {
      const double d = double(a.sector_key[j]) - double(b.sector_key[(j + s) % n]);
      cost += d * d;
    }
    if (cost < best_cost) best_cost = cost, best = s;
  }
  return best;
}

}  // namespace

bool LidarDescriptorConfig::Validate(std::string* error) const {
  if (num_rings < 1) return FailValidation(error, "lidar_descriptor.num_rings must be >= 1");
  if (num_sectors < 2) return FailValidation(error, "lidar_descriptor.num_sectors must be >= 2");
  if (!(max_radius_m > 0) || !std::isfinite(max_radius_m))
    return FailValidation(error, "lidar_descriptor.max_radius_m must be > 0 and finite");
  if (!std::isfinite(min_z_m) || !std::isfinite(max_z_m) || !(max_z_m > min_z_m))
    return FailValidation(error, "lidar_descriptor.max_z_m must be > min_z_m (both finite)");
  if (num_height_bands < 1 || num_height_bands > 32)
    return FailValidation(error, "lidar_descriptor.num_height_bands must be in [1, 32]");
  return true;
}

LidarDescriptor ComputeLidarDescriptor(const std::vector<Eigen::Vector3f>& points,
                                       const LidarDescriptorConfig& config) {
  if (!config.Validate(nullptr)) return {};
  GridBuilder grid(config);
  for (const Eigen::Vector3f& p : points) grid.Add(p.x(), p.y(), p.z());
  return grid.Finish();
}

LidarDescriptor ComputeLidarDescriptor(const pcl::PointCloud<pcl::PointXYZ>& points,
                                       const LidarDescriptorConfig& config) {
  if (!config.Validate(nullptr)) return {};
  GridBuilder grid(config);
  for (const pcl::PointXYZ& p : points) grid.Add(p.x, p.y, p.z);
  return grid.Finish();
}

DescriptorMatch DescriptorDistance(const LidarDescriptor& a, const LidarDescriptor& b, const ShiftSearch& search) {
  DescriptorMatch match;
  const int n = a.num_sectors();
  if (n == 0 || a.num_rings() == 0 || a.cells.rows() != b.cells.rows() || a.cells.cols() != b.cells.cols())
    return match;
  const Eigen::VectorXf norm_a = a.cells.colwise().norm().transpose();
  const Eigen::VectorXf norm_b = b.cells.colwise().norm().transpose();
  int first = 0, last = n - 1;  // shifts searched: first..last (mod n)
  if (search.refine_radius_sectors >= 0 && 2 * search.refine_radius_sectors + 1 < n) {
    const int coarse = CoarseShift(a, b);
    first = coarse - search.refine_radius_sectors;
    last = coarse + search.refine_radius_sectors;
  }
  for (int s = first; s <= last; ++s) {
    const int shift = ((s % n) + n) % n;
    const double d = ShiftedDistance(a, b, norm_a, norm_b, shift);
    if (s == first || d < match.distance) {
      match.distance = d;
      match.best_shift = shift;
    }
  }
  const int signed_shift = match.best_shift > n / 2 ? match.best_shift - n : match.best_shift;
  match.yaw_rad = signed_shift * kTwoPi / n;
  return match;
}

double RingKeyDistance(const LidarDescriptor& a, const LidarDescriptor& b) {
  if (a.ring_key.size() != b.ring_key.size()) return std::numeric_limits<double>::infinity();
  return double((a.ring_key - b.ring_key).norm());
}

bool LidarPlaceIndexConfig::Validate(std::string* error) const {
  if (max_keyframes < 1) return FailValidation(error, "lidar_place_index.max_keyframes must be >= 1");
  if (num_key_candidates < 1) return FailValidation(error, "lidar_place_index.num_key_candidates must be >= 1");
  return true;
}

LidarPlaceIndex::LidarPlaceIndex(const LidarPlaceIndexConfig& config) : config_(config) {}

Status LidarPlaceIndex::Add(int64_t keyframe_id, double t_s, const LidarDescriptor& descriptor) {
  const std::string where = "LidarPlaceIndex::Add(keyframe " + std::to_string(keyframe_id) + "): ";
  std::string error;
  if (!config_.Validate(&error)) return Status::Error(where + error);
  if (slot_of_id_.count(keyframe_id)) return Status::Error(where + "keyframe id already stored");
  if (entries_.size() >= config_.max_keyframes)
    return Status::Error(where + "index full (max_keyframes " + std::to_string(config_.max_keyframes) + ")");
  if (descriptor.cells.size() == 0) return Status::Error(where + "descriptor has no cells");
  if (!entries_.empty() && (descriptor.cells.rows() != entries_.front().descriptor.cells.rows() ||
                            descriptor.cells.cols() != entries_.front().descriptor.cells.cols()))
    return Status::Error(where + "descriptor size differs from the stored ones");
  slot_of_id_.emplace(keyframe_id, entries_.size());
  entries_.push_back(Entry{keyframe_id, t_s, descriptor});
  return Status::Ok();
}

std::vector<PlaceCandidate> LidarPlaceIndex::Query(const LidarDescriptor& query, const PlaceQuery& options) const {
  if (!config_.Validate(nullptr) || query.cells.size() == 0) return {};
  const std::unordered_set<int64_t> excluded(options.exclude_ids.begin(), options.exclude_ids.end());
  const double newest_t_s = options.t_s - options.exclude_recent_s;
  // Stage 1: ring-key distance to every eligible keyframe.
  std::vector<std::pair<double, size_t>> by_key;
  by_key.reserve(entries_.size());
  for (size_t i = 0; i < entries_.size(); ++i) {
    const Entry& e = entries_[i];
    if (e.t_s > newest_t_s || excluded.count(e.keyframe_id)) continue;
    const double d = RingKeyDistance(query, e.descriptor);
    if (std::isfinite(d)) by_key.emplace_back(d, i);
  }
  const size_t k = std::min(by_key.size(), size_t(config_.num_key_candidates));
  std::partial_sort(by_key.begin(), by_key.begin() + k, by_key.end());
  // Stage 2: full distance (minimum over the column shifts) of the key candidates.
  std::vector<PlaceCandidate> out;
  for (size_t c = 0; c < k; ++c) {
    const Entry& e = entries_[by_key[c].second];
    PlaceCandidate candidate{e.keyframe_id, e.t_s, by_key[c].first,
                             DescriptorDistance(query, e.descriptor, config_.shift_search)};
    if (candidate.match.distance <= options.max_distance) out.push_back(candidate);
  }
  std::stable_sort(out.begin(), out.end(), [](const PlaceCandidate& x, const PlaceCandidate& y) {
    return x.match.distance < y.match.distance;
  });
  if (out.size() > size_t(std::max(options.num_results, 0))) out.resize(size_t(std::max(options.num_results, 0)));
  return out;
}

const LidarDescriptor* LidarPlaceIndex::Find(int64_t keyframe_id) const {
  const auto it = slot_of_id_.find(keyframe_id);
  return it == slot_of_id_.end() ? nullptr : &entries_[it->second].descriptor;
}

size_t LidarPlaceIndex::BytesPerKeyframe(int num_rings, int num_sectors) {
  const size_t floats = size_t(num_rings) * size_t(num_sectors) + size_t(num_rings) + size_t(num_sectors);
  // Three heap blocks (cells, ring key, sector key), the entry itself, and an unordered_map node + bucket.
  constexpr size_t kHeapBlockOverhead = 16, kMapNode = 48;
  return floats * sizeof(float) + 3 * kHeapBlockOverhead + sizeof(Entry) + kMapNode;
}

}  // namespace rotolidar::loop
