#include "core/pipeline/free_space.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "core/util/log.hpp"
#include "core/util/validation.hpp"

namespace rotolidar {

bool FreeSpaceConfig::Validate(std::string* error) const {
  auto fail = [error](const char* m) { return FailValidation(error, m); };
  if (!(delay_s >= 0.0 && delay_s <= 60.0)) return fail("free_space.delay_s must be in [0, 60]");
  if (!(window_s >= 0.0 && window_s <= 60.0)) return fail("free_space.window_s must be in [0, 60]");
  if (bins_per_face < 3 || bins_per_face > 1000) return fail("free_space.bins_per_face must be in [3, 1000]");
  if (!(margin_m >= 0.0 && margin_m <= 10.0)) return fail("free_space.margin_m must be in [0, 10]");
  if (!(margin_per_m >= 0.0 && margin_per_m <= 1.0)) return fail("free_space.margin_per_m must be in [0, 1]");
  if (min_later_through < 1) return fail("free_space.min_later_through must be >= 1");
  if (vote_every_scans < 1) return fail("free_space.vote_every_scans must be >= 1");
  if (min_looked_bins < 1 || min_looked_bins > 9) return fail("free_space.min_looked_bins must be in [1, 9]");
  if (!(recheck_s >= 0.0 && recheck_s <= 600.0)) return fail("free_space.recheck_s must be in [0, 600]");
  if (recheck_min_through < 1 || recheck_min_through > 254)
    return fail("free_space.recheck_min_through must be in [1, 254]");
  if (!(recheck_max_range_m > 0.0 && recheck_max_range_m <= 1000.0))
    return fail("free_space.recheck_max_range_m must be in (0, 1000]");
  if (!(vacated_radius_m >= 0.0 && vacated_radius_m <= 10.0))
    return fail("free_space.vacated_radius_m must be in [0, 10]");
  if (!(vacated_min_age_s >= 0.0 && vacated_min_age_s <= vacated_max_age_s && vacated_max_age_s <= 10.0))
    return fail("free_space.vacated_min_age_s and vacated_max_age_s must satisfy 0 <= min <= max <= 10");
  if (!(vacated_max_share > 0.0 && vacated_max_share <= 1.0))
    return fail("free_space.vacated_max_share must be in (0, 1]");
  return true;
}

RangeImage::RangeImage(int bins_per_face, int min_looked_bins)
    : n_(bins_per_face),
      min_looked_(min_looked_bins),
      nearest_cm_(size_t(6 * n_ * n_), 0),
      looked_around_(size_t(6 * n_ * n_), 0) {}

inline bool RangeImage::BinOf(const Eigen::Vector3f& d, int* face, int* u, int* v) const {
  const Eigen::Vector3f a = d.cwiseAbs();
  int axis = 0;
  if (a.y() > a[axis]) axis = 1;
  if (a.z() > a[axis]) axis = 2;
  const float m = a[axis];
  if (!(m > 0.f)) return false;  // also NaN
  *face = 2 * axis + (d[axis] < 0.f ? 1 : 0);
  const float inv = 0.5f * float(n_) / m;
  const float s = d[(axis + 1) % 3] * inv + 0.5f * float(n_);  // in [0, n]
  const float t = d[(axis + 2) % 3] * inv + 0.5f * float(n_);
  *u = std::min(n_ - 1, std::max(0, int(s)));
  *v = std::min(n_ - 1, std::max(0, int(t)));
  return true;
}

void RangeImage::Clear() {
  std::fill(nearest_cm_.begin(), nearest_cm_.end(), uint16_t(0));
  std::fill(looked_around_.begin(), looked_around_.end(), uint8_t(0));
  band_sin_ = 1.f;
  band_sin2_ = 2.f;
}

void RangeImage::Add(const Eigen::Vector3f& d_sensor) {
  int face, u, v;
  if (!BinOf(d_sensor, &face, &u, &v)) return;
  band_sin_ = 1.f;  // unsealed: a new return may lie outside the band
  band_sin2_ = 2.f;
  uint16_t& nearest = nearest_cm_[Index(face, u, v)];
  // Rounded up to whole cm, at least 1 (0 marks an empty bin), at most 655.35 m.
  const uint16_t r_cm = uint16_t(std::min(65535.f, std::max(1.f, std::ceil(100.f * d_sensor.norm()))));
  if (nearest == 0) {  // a bin's first return: its 3x3 neighbours (on this face) have one more bin looked at
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du)
        if (u + du >= 0 && u + du < n_ && v + dv >= 0 && v + dv < n_)
          ++looked_around_[Index(face, u + du, v + dv)];
  }
  if (nearest == 0 || r_cm < nearest) nearest = r_cm;
}

Eigen::Vector3f RangeImage::BinCentre(int face, int u, int v) const {
  const int axis = face / 2;
  const float half = 0.5f * float(n_);
  Eigen::Vector3f c;
  c[axis] = face % 2 == 0 ? 1.f : -1.f;
  c[(axis + 1) % 3] = (float(u) + 0.5f - half) / half;  // BinOf's s and t, inverted, at |c[axis]| = 1
  c[(axis + 2) % 3] = (float(v) + 0.5f - half) / half;
  return c.normalized();
}

// The band's axis: least spread of the directions of the bins holding a return (the scatter of their centres:
// fewer than the returns, and the axis need not be exact, only the bound computed for it). Its half-width: the
// largest angle off the band's plane of such a bin, plus the reach of a 3x3 neighbourhood from a query in the outer
// bin to that bin's centre (1.5 bins per axis on the face's tangent plane at distance 1, where a length bounds the
// angle).
void RangeImage::Seal() {
  std::vector<Eigen::Vector3f> centres;
  centres.reserve(4096);
  Eigen::Matrix3f scatter = Eigen::Matrix3f::Zero();
  for (int face = 0; face < 6; ++face)
    for (int v = 0; v < n_; ++v)
      for (int u = 0; u < n_; ++u)
        if (nearest_cm_[Index(face, u, v)] != 0) {
          centres.push_back(BinCentre(face, u, v));
          scatter.noalias() += centres.back() * centres.back().transpose();
        }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig(scatter);
  band_axis_ = eig.eigenvectors().col(0).normalized();
  if (!band_axis_.allFinite()) return;  // unbounded
  float max_cos = 0.f;
  for (const Eigen::Vector3f& c : centres) max_cos = std::max(max_cos, std::abs(c.dot(band_axis_)));
  const double reach_rad = 1.5 * std::sqrt(2.0) * 2.0 / n_ + 1e-3;  // + float rounding
  const double half_width_rad = std::asin(std::min(1.0, double(max_cos))) + reach_rad;
  if (half_width_rad >= 0.5 * M_PI) return;  // the returns span the sphere: no bound
  band_sin_ = float(std::sin(half_width_rad));
  band_sin2_ = band_sin_ * band_sin_;
}

RangeImage::Verdict RangeImage::JudgeInBand(const Eigen::Vector3f& d_sensor, float margin_m,
                                            float margin_per_m) const {
  int face, u, v;
  if (!BinOf(d_sensor, &face, &u, &v)) return Verdict::kUnknown;
  const size_t bin = Index(face, u, v);
  const uint16_t centre = nearest_cm_[bin];
  const bool looked = looked_around_[bin] >= min_looked_;
  if (centre == 0 && !looked) return Verdict::kUnknown;  // not looked at: no range needed
  const float r_m = d_sensor.norm();
  const float r_cm = 100.f * r_m, margin_cm = 100.f * (margin_m + margin_per_m * r_m);
  if (centre > 0 && std::abs(float(centre) - r_cm) <= margin_cm) return Verdict::kHit;
  if (!looked) return Verdict::kUnknown;  // outside the scan's band (most of the sphere for one rotary scan)
  if (u == 0 || v == 0 || u == n_ - 1 || v == n_ - 1) return Verdict::kUnknown;  // neighbours on another face
  const float beyond_cm = r_cm + margin_cm;
  int through = 0;
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const uint16_t b = nearest_cm_[Index(face, u + du, v + dv)];
      if (b == 0) continue;  // no return in this bin: not looked at
      if (float(b) <= beyond_cm) return Verdict::kUnknown;  // something at or before the point
      ++through;
    }
  return through >= min_looked_ ? Verdict::kSeenThrough : Verdict::kUnknown;
}

FreeSpaceFilter::FreeSpaceFilter(const FreeSpaceConfig& config, const Eigen::Vector3d& origin_base)
    : config_(config), origin_base_(origin_base.cast<float>()) {
  std::string why;
  ROTOLIDAR_CHECK(config_.Validate(&why), why);
}

void BuildRangeImage(const std::vector<ScanPoint>& points, const Eigen::Vector3f& origin_base, RangeImage* image) {
  image->Clear();
  for (const ScanPoint& p : points)
    if (p.p_base.allFinite()) image->Add(p.p_base - origin_base);
  image->Seal();
}

const RangeImage& FreeSpaceFilter::PrepareImage(const std::vector<ScanPoint>& points) {
  if (!prepared_) prepared_.emplace(TakeImage());
  BuildRangeImage(points, origin_base_, &*prepared_);
  prepared_points_ = points.size();
  has_prepared_ = true;
  return *prepared_;
}

void FreeSpaceFilter::AddScan(Seconds t_s, const Pose3& T_world_base, const std::vector<ScanPoint>& points,
                              double max_range_m) {
  const bool prepared = has_prepared_ && prepared_points_ == points.size();
  Scan scan{t_s, T_world_base, Eigen::Matrix3f(), Eigen::Vector3f(), TakeImage(), {}};
  if (prepared) std::swap(scan.image, *prepared_);
  else BuildRangeImage(points, origin_base_, &scan.image);
  const Pose3 T_base_world = T_world_base.inverse();
  scan.R_base_world = T_base_world.linear().cast<float>();
  scan.t_sensor_world = T_base_world.translation().cast<float>() - origin_base_;
  scan.waiting_world.reserve(points.size());
  for (const ScanPoint& p : points)
    if (p.p_base.allFinite() && p.range_m <= max_range_m)
      scan.waiting_world.push_back(T_world_base * p.p_base.cast<double>());
  scans_.push_back(std::move(scan));
  has_prepared_ = false;  // the next AddScan builds its own unless PrepareImage runs again
}

// One image's votes (JudgePoints) counted per point.
void FreeSpaceFilter::Vote(const Scan& scan, const Eigen::Matrix3Xf& p_world, bool later,
                           std::vector<uint16_t>* through, std::vector<uint16_t>* later_through,
                           std::vector<uint16_t>* hits) const {
  const PlacedImage placed{&scan.image, scan.R_base_world, scan.t_sensor_world};
  JudgePoints(placed, p_world, float(config_.margin_m), float(config_.margin_per_m),
              std::numeric_limits<float>::infinity(), [&](size_t i, RangeImage::Verdict verdict) {
                if (verdict == RangeImage::Verdict::kHit) {
                  ++(*hits)[i];
                  return;
                }
                ++(*through)[i];
                if (later && later_through) ++(*later_through)[i];
              });
}

PlacedImage FreeSpaceFilter::Newest() const {
  if (scans_.empty()) return {};
  const Scan& scan = scans_.back();
  return PlacedImage{&scan.image, scan.R_base_world, scan.t_sensor_world};
}

// Votes of every vote_every_scans-th scan within window_s of scans_[k] (k itself excluded), one image at a time
// (its bins stay in cache). Dynamic when the space was seen free after the point by min_later_through scans (the
// object left, however long it stood there), or when at least one scan saw through it and no more hit it than
// saw through it (it passed by within the window).
void FreeSpaceFilter::MarkDynamic(size_t k) {
  const size_t n = candidates_.size();
  through_.assign(n, 0);
  later_through_.assign(n, 0);
  hits_.assign(n, 0);
  dynamic_.assign(n, 0);
  candidates_f_.resize(3, Eigen::Index(n));
  for (size_t i = 0; i < n; ++i) candidates_f_.col(Eigen::Index(i)) = candidates_[i].cast<float>();
  const size_t stride = size_t(config_.vote_every_scans);
  for (size_t j = k % stride; j < scans_.size(); j += stride) {
    if (j == k || std::abs(scans_[j].t_s - scans_[k].t_s) > config_.window_s) continue;
    Vote(scans_[j], candidates_f_, j > k, &through_, &later_through_, &hits_);
  }
  for (size_t i = 0; i < n; ++i)
    dynamic_[i] = later_through_[i] >= config_.min_later_through || PassedBy(through_[i], hits_[i]);
}

bool FreeSpaceFilter::SeenThroughBefore(Seconds t_s, const Eigen::Vector3d& p_world) const {
  std::vector<uint8_t> seen;
  SeenThroughBefore(t_s, Eigen::Matrix3Xf(p_world.cast<float>()), &seen);
  return seen[0] != 0;
}

void FreeSpaceFilter::SeenThroughBefore(Seconds t_s, const Eigen::Matrix3Xf& p_world,
                                        std::vector<uint8_t>* seen) const {
  const size_t n = size_t(p_world.cols());
  std::vector<uint16_t> through(n, 0), hits(n, 0);
  int eligible = 0;
  for (auto it = scans_.rbegin(); it != scans_.rend(); ++it) {  // newest first: every vote_every_scans-th votes
    const Scan& scan = *it;
    if (scan.t_s >= t_s) continue;
    if (t_s - scan.t_s > config_.window_s) break;
    if (eligible++ % config_.vote_every_scans != 0) continue;
    Vote(scan, p_world, false, &through, nullptr, &hits);
  }
  seen->resize(n);
  for (size_t i = 0; i < n; ++i) (*seen)[i] = PassedBy(through[i], hits[i]) ? 1 : 0;
}

// A dropped scan's image, cleared, or a new one (an image is ~150 kB: reusing it spares the allocator and the
// kernel's page clearing).
RangeImage FreeSpaceFilter::TakeImage() {
  if (spare_images_.empty()) return RangeImage(config_.bins_per_face, config_.min_looked_bins);
  RangeImage image = std::move(spare_images_.back());
  spare_images_.pop_back();
  image.Clear();
  return image;
}

// Images stay while a waiting scan's window or SeenThroughBefore may still need them.
void FreeSpaceFilter::DropOld() {
  if (scans_.empty()) return;
  const Seconds oldest_needed =
      (released_ < scans_.size() ? scans_[released_].t_s : scans_.back().t_s) - config_.window_s;
  while (released_ > 0 && scans_.front().t_s < oldest_needed) {
    spare_images_.push_back(std::move(scans_.front().image));
    scans_.pop_front();
    --released_;
  }
}

}  // namespace rotolidar
