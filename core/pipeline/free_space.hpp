#pragma once
// Moving objects out of the maps by free-space consistency: a point is dynamic when another scan's rays passed
// through where it was (the ray went on beyond it), i.e. the space it occupied was seen empty at another time.
// This is the visibility test of "Remove, then Revert" (Kim & Kim, IROS 2020) and of the range-image checks of
// Pomerleau et al. ("Long-term 3D map maintenance in dynamic environments", ICRA 2014), run online against the
// scans around each point instead of offline against a finished map: cheap (no ray traversal of a voxel grid,
// one projection per point and scan), exact in what it assumes (a return proves the segment before it is free),
// and blind only where no scan looked (what nothing saw through stays; registration's robust loss carries it).
//
// Each scan becomes a range image: a cube map of directions from the sensor origin (no trigonometry; ~1 deg bins
// at a face centre, ~0.5 deg at the corners) holding per bin the nearest return. A point p is judged against an
// image from the 3x3 bins around p's direction:
//   seen through: at least min_looked_bins of the 9 bins have a return, and every return there is beyond
//                 |p| + margin (bins without a return were not looked at: a rotary scan's rays are ~2 deg apart);
//   hit:          the centre bin's nearest return is within margin of |p| (the same surface again);
//   unknown:      otherwise (not looked at, occluded, or near a face border).
// The 3x3 minimum keeps grazing surfaces (a floor seen at a shallow angle has nearer returns in the neighbouring
// bins) and edges (the nearer side of a depth edge is a neighbour) from being called free. A point is dynamic
// when min_later_through later images saw through it (the object left, however long it stood), or when at
// least one image saw through it and no more images hit it than saw through it (it passed by).
//
// Points already in the dense map go on being judged by later scans for a while (MapRecheck,
// core/pipeline/map_recheck.hpp, through Newest() and JudgePoints).
//
// Frames: images live in the scan's base frame with their origin at the sensor origin there (RigCalib: the
// lidar origin averaged over the rotor turn; a mount off the motor axis turns on a circle whose radius adds to
// the margin). Points are judged in the world frame with each image's T_world_base.
// Thread safety: none.
#include <algorithm>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types/geometry.hpp"
#include "core/types/scan_point.hpp"
#include "core/types/time.hpp"

namespace rotolidar {

struct FreeSpaceConfig {
  /// Off: every point enters the maps at once, untested (the Estimator then does not use this filter).
  bool enabled = true;
  /// Dense-map points wait this long before they enter, so that later scans can see through them [s]. A
  /// rotary rig looks along one direction twice per rotor turn (2.4 s at 2.6 rad/s): 2.5 s gives every point
  /// two later looks. Measured on lab_people (20 s, typical, seed 1): dynamic voxels reaching the dense map
  /// 10 % with 1.5 s, 4.6 % with 2.5 s.
  double delay_s = 2.5;
  /// Scans within this time of a point's scan vote on it [s].
  double window_s = 2.5;
  int bins_per_face = 90;     ///< cube-map resolution: 90 / 90 = 1 deg at a face centre
  /// Bins of a 3x3 neighbourhood that must hold a return (all beyond the point) to call it seen through: 4 of
  /// 9 (the rays of one rotary scan are ~2 deg apart, so 1 deg bins are often empty between them; 9 of 9 let
  /// twice as many dynamic voxels through on lab_people, 4 lets 0.4 % of static points out).
  int min_looked_bins = 4;
  double margin_m = 0.10;     ///< a ray must pass this far beyond a point to see through it [m] (noise, pose)
  double margin_per_m = 0.01; ///< plus this much per metre of range (angular pose error, beam divergence)
  /// Later scans that must see through a point to call it left behind (2: one scan's pose error or a thin
  /// structure slipping between one scan's rays does not remove a static point).
  int min_later_through = 2;
  /// Every this many scans of the window vote (a rotary rig's consecutive scans share half their band, so
  /// every other one sees nearly all a point's neighbours do, at half the cost).
  int vote_every_scans = 2;
  /// Also drop the scan's own edge / planar features that stand where earlier scans saw free space, judged at
  /// the predicted pose, before registration matches them (a person walking towards the rig is otherwise
  /// matched against the walls it hides until its points are kept out of the map). Applies once the IMU
  /// predicts the pose (the Estimator's sliding window runs) or, without the IMU, with the LiDAR-only velocity
  /// window (EstimatorConfig::lidar_only_velocity_window_s > 0); the last two scans' twist is too coarse for it.
  bool screen_scan_features = true;
  /// Dense-map points go on being judged by every vote_every_scans-th new scan for this long after they
  /// entered the map (MapRecheck, core/pipeline/map_recheck.hpp) [s]; 0 = off. A point whose spot the delay's
  /// window never saw through (the object stood there, or the rig did not look back in time) leaves the map
  /// once later scans see through it. See recheck_min_through for the rule.
  double recheck_s = 8.0;
  /// Scans in a row (no scan hitting the point between them) that must see through a dense-map point to take
  /// it out again. A hit resets the count: a static point is hit at most looks, so pose error or a thin
  /// structure slipping between two looks' rays does not remove it.
  int recheck_min_through = 2;
  /// The recheck judges a point only from scans within this range of it [m]. Farther, a floor or ceiling is
  /// seen at a grazing angle, where a small pose or beam-angle error moves the return by more than the margin
  /// (the error grows with the square of the range), and static points were seen through. Measured on
  /// lab_people 20 s and the first 3 min of the 30 min parking walk (docs/estimator.md): no cap lost 1.6 and
  /// 1.9 points of floor completeness; 12 m keeps most of the gain at 0.6 and 0.0 points.
  double recheck_max_range_m = 12.0;
  /// Scan features within this distance of a place that the recent scans' features held and the present scan
  /// sees through are dropped before registration (VacatedScreen, core/pipeline/vacated_screen.hpp: objects
  /// moving with the rig) [m]; 0 = off. It spans what a walker moves in vacated_max_age_s plus its body's depth.
  /// Busy corridor 20 s, typical, seeds 1-6: ATE 1.0-1.4 m without it, 0.009-0.020 m with 0.5, 0.013-0.020 m
  /// with 0.7, 0.011-0.028 m with 1.0; the other scenes within their seed-to-seed spread (docs/estimator.md).
  double vacated_radius_m = 0.7;
  /// The recent scans judged are this old at least [s]: an object must have moved beyond the margin since
  /// (walking at 1.3 m/s, 0.2 m in 0.15 s).
  double vacated_min_age_s = 0.15;
  double vacated_max_age_s = 0.6;  ///< ... and at most [s] (a slower object, 0.3 m/s, moves 0.18 m in 0.6 s)
  /// When more than this share of a scan's features would be dropped, the prediction is taken to be off (static
  /// surfaces then look vacated along the motion) and none are.
  double vacated_max_share = 0.3;
  bool Validate(std::string* error) const;  ///< false with the offending field named in *error
};

/// A cube-map range image of one scan (see the file comment).
///
/// Band bound: one scan of a rotary rig (or of any multi-beam LiDAR) looks along a belt of directions, a fan
/// swept about the head's spin axis, and most of the sphere holds no return. Seal() finds the belt's axis n
/// (the direction along which the bins holding a return spread least: the eigenvector of the smallest
/// eigenvalue of their directions' scatter) and the largest |cos| between n and any such bin, widened by the
/// angular reach of a 3x3 neighbourhood. A direction beyond that bound has no return in its 3x3 bins, so Judge
/// answers kUnknown with one dot product instead of a bin lookup: the same verdicts, exactly, at a fraction of the
/// cost. A scan covering the whole sphere gets no bound (every direction is tested as before).
class RangeImage {
 public:
  enum class Verdict { kUnknown, kHit, kSeenThrough };
  RangeImage(int bins_per_face, int min_looked_bins);
  /// Empties the image (keeps its memory), unsealed.
  void Clear();
  /// Adds a return at d_sensor [m] (the point minus the sensor origin, in the image's frame). Unseals.
  void Add(const Eigen::Vector3f& d_sensor);
  /// After the last Add: computes the band bound (see the class comment). Optional: Judge's verdicts are the
  /// same either way, only faster sealed.
  void Seal();
  /// How this image sees a point at d_sensor (same frame). The margin is margin_m + margin_per_m * |d_sensor|
  /// [m] (FreeSpaceConfig's margin_m and margin_per_m).
  Verdict Judge(const Eigen::Vector3f& d_sensor, float margin_m, float margin_per_m = 0.f) const {
    return OutsideBand(d_sensor) ? Verdict::kUnknown : JudgeInBand(d_sensor, margin_m, margin_per_m);
  }
  /// True when sealed and d_sensor lies outside the band: Judge would answer kUnknown.
  bool OutsideBand(const Eigen::Vector3f& d_sensor) const {
    const float c = d_sensor.dot(band_axis_);
    return c * c > band_sin2_ * d_sensor.squaredNorm();  // never true unsealed (band_sin2_ > 1)
  }
  /// Judge without the band test (the caller made it, e.g. for many points at once).
  Verdict JudgeInBand(const Eigen::Vector3f& d_sensor, float margin_m, float margin_per_m) const;
  /// The sealed band's axis (unit, image frame) and the sine of its half-width: directions d with
  /// |d.n| > band_sin * |d| are outside; band_sin >= 1 when unsealed or unbounded.
  const Eigen::Vector3f& band_axis() const { return band_axis_; }
  float band_sin() const { return band_sin_; }
  float band_sin2() const { return band_sin2_; }  ///< band_sin()^2, or > 1 when unbounded

 private:
  /// Bin of a direction: face 0..5 and (u, v) in [0, bins_per_face); false for the zero vector.
  bool BinOf(const Eigen::Vector3f& d, int* face, int* u, int* v) const;
  /// The unit direction through the centre of bin (face, u, v).
  Eigen::Vector3f BinCentre(int face, int u, int v) const;
  size_t Index(int face, int u, int v) const { return size_t((face * n_ + v) * n_ + u); }
  int n_;
  int min_looked_;
  std::vector<uint16_t> nearest_cm_;  ///< per bin the nearest return [cm, rounded up]; 0 = no return
  std::vector<uint8_t> looked_around_;  ///< per bin how many of its 3x3 bins (on its face) hold a return
  Eigen::Vector3f band_axis_ = Eigen::Vector3f::UnitZ();
  float band_sin_ = 1.f;     ///< see band_sin()
  float band_sin2_ = 2.f;    ///< band_sin_^2, or > 1 for "no bound"
};

/// Clears *image, adds the finite points of a scan (p_base - origin_base, base frame [m]) and seals it.
void BuildRangeImage(const std::vector<ScanPoint>& points, const Eigen::Vector3f& origin_base, RangeImage* image);

/// One scan's image placed in the world: a world point p is judged at d = R_base_world * p + t_sensor_world.
struct PlacedImage {
  const RangeImage* image = nullptr;
  Eigen::Matrix3f R_base_world = Eigen::Matrix3f::Identity();
  Eigen::Vector3f t_sensor_world = Eigen::Vector3f::Zero();
};

/// Judges the points p_world (3xN, world [m]) against one placed image: the band test for all of them first
/// (vectorised: d = R p + t, d.n, |d|^2), then the bins for the few in the band. Points farther than
/// max_range_m from the sensor are left unknown. Calls on_verdict(i, verdict) for each point i that is hit or
/// seen through (not for kUnknown).
template <class OnVerdict>
void JudgePoints(const PlacedImage& placed, const Eigen::Matrix3Xf& p_world, float margin_m, float margin_per_m,
                 float max_range_m, OnVerdict&& on_verdict) {
  const RangeImage& image = *placed.image;
  constexpr Eigen::Index kBlock = 256;
  Eigen::Matrix<float, 3, kBlock> d;
  Eigen::Matrix<float, 1, kBlock> along, sq_norm;
  const float sin2 = image.band_sin2(), max_sq = max_range_m * max_range_m;
  for (Eigen::Index begin = 0; begin < p_world.cols(); begin += kBlock) {
    const Eigen::Index n = std::min(kBlock, p_world.cols() - begin);
    d.leftCols(n).noalias() = placed.R_base_world * p_world.middleCols(begin, n);
    d.leftCols(n).colwise() += placed.t_sensor_world;
    along.leftCols(n).noalias() = image.band_axis().transpose() * d.leftCols(n);
    sq_norm.leftCols(n) = d.leftCols(n).colwise().squaredNorm();
    for (Eigen::Index j = 0; j < n; ++j) {
      if (along[j] * along[j] > sin2 * sq_norm[j] || sq_norm[j] > max_sq) continue;  // outside the band, too far
      const RangeImage::Verdict verdict = image.JudgeInBand(d.col(j), margin_m, margin_per_m);
      if (verdict != RangeImage::Verdict::kUnknown) on_verdict(size_t(begin + j), verdict);
    }
  }
}

/// Counters of one call (ScanReport reports them per scan).
struct FreeSpaceCounts {
  size_t judged = 0;   ///< points tested against the images
  size_t dynamic = 0;  ///< of those, found dynamic (kept out of the map)
  size_t removed = 0;  ///< dense-map points taken out again by the recheck (MapRecheck)
  FreeSpaceCounts& operator+=(const FreeSpaceCounts& o) {
    judged += o.judged;
    dynamic += o.dynamic;
    removed += o.removed;
    return *this;
  }
};

/// The scans around the present: their range images and poses, plus the points still waiting for the dense map.
class FreeSpaceFilter {
 public:
  /// origin_base: the sensor origin in the base frame [m]. `config` must Validate (ROTOLIDAR_CHECKed).
  FreeSpaceFilter(const FreeSpaceConfig& config, const Eigen::Vector3d& origin_base);

  /// A processed scan: its pose T_world_base (base frame at t_s) and its points (p_base in that frame); its
  /// image is built, and points with range_m <= max_range_m wait for the dense map.
  /// When PrepareImage was called for these points since the last AddScan, its image is taken, not rebuilt.
  void AddScan(Seconds t_s, const Pose3& T_world_base, const std::vector<ScanPoint>& points, double max_range_m);
  /// Builds the image of the scan that the next AddScan will add (the same points, base frame) ahead of it, so
  /// that it can judge before registration (VacatedScreen). Valid until AddScan.
  const RangeImage& PrepareImage(const std::vector<ScanPoint>& points);
  /// True when scans before t_s (within window_s; every vote_every_scans-th, newest first) saw through p_world
  /// and no more hit it: a point arriving where space was free.
  bool SeenThroughBefore(Seconds t_s, const Eigen::Vector3d& p_world) const;
  /// SeenThroughBefore for each column of p_world (world [m]), one image at a time (its bins stay in cache):
  /// (*seen)[i] = 1 or 0; resized.
  void SeenThroughBefore(Seconds t_s, const Eigen::Matrix3Xf& p_world, std::vector<uint8_t>* seen) const;
  /// Hands the waiting points of scans older than latest - delay_s (all of them with `flush`) to `accept`
  /// (world frame), except those the scans around them found dynamic; drops images no longer needed.
  /// `wanted(p)` may skip the test for points the map would not take anyway (e.g. its voxel is full).
  template <class Wanted, class Accept>
  FreeSpaceCounts Release(bool flush, Wanted&& wanted, Accept&& accept);
  /// The newest scan's image, placed (image null before the first AddScan). Valid until the next AddScan.
  PlacedImage Newest() const;

 private:
  struct Scan {
    Seconds t_s;
    Pose3 T_world_base;
    Eigen::Matrix3f R_base_world;  ///< for judging: d = R_base_world * p_world + t_sensor_world
    Eigen::Vector3f t_sensor_world;
    RangeImage image;
    std::vector<Eigen::Vector3d> waiting_world;  ///< points not yet released [world]
  };
  /// dynamic_[i] for each candidates_[i] of scans_[k]: the votes of the scans around it (the rule above).
  void MarkDynamic(size_t k);
  /// One image's votes on points p_world (3xN, world): ++(*through)[i] (and ++(*later_through)[i] when `later`)
  /// where it saw through point i, ++(*hits)[i] where it hit it. later_through may be null.
  void Vote(const Scan& scan, const Eigen::Matrix3Xf& p_world, bool later, std::vector<uint16_t>* through,
            std::vector<uint16_t>* later_through, std::vector<uint16_t>* hits) const;
  RangeImage TakeImage();
  /// The "passed by" half of the rule: at least one scan saw through the point and no more hit it.
  static bool PassedBy(int through, int hits) { return through > 0 && through >= hits; }
  void DropOld();

  FreeSpaceConfig config_;
  Eigen::Vector3f origin_base_;
  std::deque<Scan> scans_;  ///< time order
  std::vector<RangeImage> spare_images_;  ///< images of dropped scans, for reuse
  std::optional<RangeImage> prepared_;     ///< PrepareImage's image (kept for its memory)
  size_t prepared_points_ = 0;             ///< how many points it was built from
  bool has_prepared_ = false;              ///< PrepareImage ran since the last AddScan
  size_t released_ = 0;     ///< scans_[0, released_) have handed their points on
  // Release's buffers (kept to reuse their memory): the released scan's points to judge and their votes.
  std::vector<Eigen::Vector3d> candidates_;
  Eigen::Matrix3Xf candidates_f_;  ///< candidates_ as floats, one per column
  std::vector<uint16_t> through_, later_through_, hits_;
  std::vector<uint8_t> dynamic_;
};

template <class Wanted, class Accept>
FreeSpaceCounts FreeSpaceFilter::Release(bool flush, Wanted&& wanted, Accept&& accept) {
  FreeSpaceCounts counts;
  while (released_ < scans_.size() &&
         (flush || scans_[released_].t_s <= scans_.back().t_s - config_.delay_s)) {
    Scan& scan = scans_[released_];
    candidates_.clear();
    for (const Eigen::Vector3d& p : scan.waiting_world)
      if (wanted(p)) candidates_.push_back(p);
    counts.judged += candidates_.size();
    MarkDynamic(released_);
    for (size_t i = 0; i < candidates_.size(); ++i) {
      if (dynamic_[i]) {
        ++counts.dynamic;
        continue;
      }
      accept(candidates_[i]);
    }
    scan.waiting_world = std::vector<Eigen::Vector3d>();
    ++released_;
  }
  DropOld();
  return counts;
}

}  // namespace rotolidar
