#pragma once
// Depth of visual features: from the LiDAR where it saw the feature's surface, by triangulation otherwise.
//
// LiDAR depth (after LVI-SAM, Shan et al., "LVI-SAM: Tightly-coupled Lidar-Visual-Inertial Odometry via Smoothing
// and Mapping", ICRA 2021, Sec. III-B "Depth association"): the LiDAR points of one image, deskewed to the image
// time and in the camera frame, are projected onto the unit sphere and indexed once by a kd-tree
// (pcl::KdTreeFLANN over the unit bearings: the chord between bearings grows monotonically with their angle).
// For each feature the nearest bearings within search_radius_deg are taken; the feature is rejected when they are
// too few ("no points"), when their ranges spread more than max_depth_spread_m (a depth edge: foreground and
// background mixed), when their bearings lie on one scan line (the plane's tilt about that line is unknown), when
// the least-squares plane through them leaves an RMS range residual above max_plane_rms_m (a corner or clutter),
// when the feature's ray meets that plane at less than min_incidence_deg (grazing) or when the depth along the ray
// lies outside [min_depth_m, max_depth_m].
// Departure from LVI-SAM: it intersects the ray with the plane through the 3 nearest points. A single VLP-16 scan
// has its rings 2 deg apart but its points 0.2 deg apart along a ring, so the 3 nearest bearings are nearly always
// consecutive points of one ring, i.e. collinear, and their plane is noise. Here up to max_neighbours points (32:
// both adjacent rings) are fitted by least squares: the plane is defined, the range noise is averaged down (3 cm
// noise gives ~4 mm median depth error in the tests), and the residual is a planarity check that 3 points cannot
// give (their plane fits them exactly). The fit minimises the range residuals along each point's own bearing (the
// plane as w . p = 1, whose inverse range is linear in the bearing), i.e. the LiDAR's noise model, not the
// point-plane distances of a PCA plane, which turns towards the rays when a patch is narrow against the noise.
// Known limit: two rings on two surfaces (e.g. a floor ring and a wall ring at a concave corner) also fit one
// plane when their ranges spread less than max_depth_spread_m; the tests measure up to 10 cm error there.
//
// Triangulation fallback: N >= 2 normalised observations with camera poses T_world_cam_k. Linear start: the
// midpoint of the rays (the point closest to all rays in the least-squares sense, a 3x3 solve), then Gauss-Newton
// steps on the normalised-plane reprojection error. Rejected for too little parallax (the largest angle between two
// rays), a point behind any camera, or a reprojection RMS above max_reprojection_rms_px.
//
// Frames: T_a_b maps points from frame b into frame a (docs/frames.md). cam = optical frame (z forward, x right,
// y down). A feature's normalised coordinates are (x/z, y/z) of its undistorted ray in the cam frame.
// Units: metres, radians inside; configs name their units (_m, _deg, _px). "depth" = z in the cam frame, "range"
// = distance from the cam origin.
// Ownership: LidarDepthMap copies the points it keeps; the inputs may be freed after Build.
// Thread safety: Build is not; const Query calls may run concurrently on one built map (kd-tree searches are
// const). TriangulateFeature has no shared state.
// Failure: reported in the result structs (status, valid = false), never thrown. Invalid configs, non-finite points
// (dropped) and non-finite features or poses (status kInvalidInput) never crash.
// Cost: Build ~ O(P log P) for P points, a Query one 32-nearest-neighbour search and a 3x3 solve. Measured (tests,
// one core): Build of 13.6k points 1.6 ms, 100 queries 0.3 ms.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types/geometry.hpp"

namespace rotolidar::visual {

/// Why a LiDAR depth is missing (kValid when it is not).
enum class DepthStatus {
  kValid,
  kInvalidConfig,  ///< LidarDepthConfig::Validate failed (the map holds no points)
  kInvalidInput,   ///< the feature's coordinates are not finite
  kNoPoints,       ///< fewer than min_neighbours LiDAR bearings within search_radius_deg
  kDepthEdge,      ///< the neighbours' ranges spread more than max_depth_spread_m
  kCollinear,      ///< the neighbours' bearings lie on one line (one scan line): the plane is undetermined
  kNotPlanar,      ///< the least-squares plane's RMS residual exceeds max_plane_rms_m
  kGrazing,        ///< the ray meets the plane at less than min_incidence_deg
  kOutOfRange,     ///< the depth lies outside [min_depth_m, max_depth_m] (or behind the camera)
};
const char* ToString(DepthStatus status);

struct LidarDepthConfig {
  /// Neighbour search radius about the feature's ray [deg]. A single VLP-16 scan has its rings 2 deg apart (also
  /// seen from a camera near the LiDAR), so 2.5 deg reaches two rings around every ray, also one lying on a ring
  /// (with 2.0 deg, 6 of the tests' 400 wall rays found one ring only). LVI-SAM's gate is ~2.5 deg too.
  double search_radius_deg = 2.5;
  /// Nearest bearings used for the plane. 32: a VLP-16 ring holds 21 points (0.2 deg apart) within 2 deg of a ray
  /// on it, so 32 still takes ~11 of the next rings; more would only widen the patch in a dense (accumulated) cloud.
  int max_neighbours = 32;
  /// Fewest neighbours for a plane. 5: a plane through 3 points fits them exactly and cannot reveal a corner; 5
  /// leave 2 residual degrees of freedom for the planarity check.
  int min_neighbours = 5;
  /// Depth-edge gate on the neighbours' range spread (max - min) [m]. LVI-SAM uses 2 m; 1 m also catches a box 1 m in
  /// front of a wall. Cost: an oblique surface at incidence a spreads up to ~ r * 5 deg / tan(a) over the patch, so
  /// surfaces beyond r ~ 11 m * tan(a) may be rejected too (6.6 m at 30 deg; floors far away).
  double max_depth_spread_m = 1.0;
  /// Collinearity gate: the neighbours' bearings must spread at least this much (std, across their main direction)
  /// [deg]. One scan line spreads < 0.01 deg across itself over the patch; two VLP-16 rings 2 deg apart spread
  /// >= 0.35 deg even with 1 point of 32 on the second ring.
  double min_bearing_spread_deg = 0.1;
  /// Planarity gate: RMS range residual of the neighbours to their plane, along their bearings [m]. ~1.7x the
  /// VLP-16's +-3 cm range accuracy (the tests' 3 cm range noise gives 0.03 +- 0.005 m); a corner or a ring
  /// crossing an edge gives more.
  double max_plane_rms_m = 0.05;
  /// Grazing gate: the smallest angle between the ray and the plane [deg]. At incidence a the depth changes by
  /// range / tan(a) per radian across the image: a 0.5 px feature error (1e-3 rad) costs 2.8 cm at 5 m and 10 deg,
  /// and any curvature inside the patch is magnified alike. (Near and dense, the fitted tilt is noisy: the tests'
  /// 3 cm noise at 1-2 m over a few-cm patch scatters it by several degrees.)
  double min_incidence_deg = 10.0;
  /// Accepted depth (z along the optical axis) [m]. Also, only points with z > min_depth_m are indexed.
  /// 0.4 m: the VLP-16 blind zone; 100 m: its rated range.
  double min_depth_m = 0.4;
  double max_depth_m = 100.0;

  /// True when every field is usable; otherwise false with a message naming the field in *error.
  bool Validate(std::string* error) const;
};

/// LiDAR depth of one feature. The diagnostics are filled as far as the query got, also when invalid.
struct FeatureDepth {
  bool valid = false;  ///< status == kValid
  DepthStatus status = DepthStatus::kNoPoints;
  double depth_m = 0.0;      ///< z of the ray's intersection with the plane, cam frame [m]
  double range_m = 0.0;      ///< distance from the cam origin to that intersection [m]
  int num_neighbours = 0;    ///< bearings within the search radius used (at most max_neighbours)
  double range_spread_m = 0.0;  ///< max - min range of the neighbours [m]
  double plane_rms_m = 0.0;     ///< RMS range residual of the neighbours to their plane [m]
  double incidence_deg = 0.0;   ///< angle between the ray and the plane [deg]
};

/// The LiDAR points of one image, indexed by bearing; build once per image, query per feature.
class LidarDepthMap {
 public:
  explicit LidarDepthMap(const LidarDepthConfig& config = {});
  ~LidarDepthMap();
  LidarDepthMap(LidarDepthMap&&) noexcept;
  LidarDepthMap& operator=(LidarDepthMap&&) noexcept;

  /// Indexes points given in the cam frame at the image time [m] (deskewed). Non-finite points and points with
  /// z <= min_depth_m are dropped. Replaces the previous points. Returns the number kept (0 for an invalid config).
  size_t Build(const std::vector<Eigen::Vector3d>& points_cam);
  /// Same for points in another frame (e.g. lidar, deskewed to the image time): p_cam = T_cam_points * p.
  size_t Build(const std::vector<Eigen::Vector3d>& points, const Pose3& T_cam_points);

  /// Depth of a feature from its undistorted normalised coordinates (x/z, y/z) in the cam frame.
  FeatureDepth Query(const Eigen::Vector2d& xy_normalised) const;
  std::vector<FeatureDepth> Query(const std::vector<Eigen::Vector2d>& xy_normalised) const;

  size_t size() const { return points_.size(); }
  bool config_valid() const { return config_error_.empty(); }
  const std::string& config_error() const { return config_error_; }  ///< empty when the config is valid

 private:
  struct Index;
  LidarDepthConfig config_;
  std::string config_error_;
  std::vector<Eigen::Vector3d> points_;  ///< kept points, cam frame
  std::unique_ptr<Index> index_;         ///< kd-tree over the unit bearings of points_
};

/// The bearings that can be a neighbour of some feature's ray: within radius_rad of it. A LidarDepthMap built over
/// only the points Contains accepts answers those features' queries as one built over all points does, since a
/// query takes the nearest bearings within search_radius_deg (pass that radius). Building the index over the few
/// thousand points near a handful of new features instead of a whole accumulated cloud (~10^5 points) is what
/// makes a per-state depth query cheap. Contains costs one 3-vector product per feature.
class RayNeighbourhood {
 public:
  /// xy_normalised: the features' undistorted normalised coordinates (cam frame); radius_rad in (0, pi/2).
  RayNeighbourhood(const std::vector<Eigen::Vector2d>& xy_normalised, double radius_rad);
  /// Whether the bearing of p_cam (cam frame, any range > 0) lies within the radius of some feature's ray. The
  /// radius is widened by 1e-4 rad so that float rounding never drops a neighbour at its edge.
  bool Contains(const Eigen::Vector3f& p_cam) const {
    return rays_.rows() > 0 && (rays_ * p_cam).maxCoeff() >= min_cos_ * p_cam.norm();
  }

 private:
  Eigen::Matrix<float, Eigen::Dynamic, 3> rays_;  ///< the features' unit bearings, one per row
  float min_cos_ = 1.0f;
};

/// Why a triangulation failed (kValid when it did not).
enum class TriangulationStatus {
  kValid,
  kInvalidConfig,      ///< TriangulationConfig::Validate failed
  kInvalidInput,       ///< < 2 observations, sizes differ, or a non-finite observation or pose
  kLowParallax,        ///< the largest angle between two rays is below min_parallax_deg
  kDegenerate,         ///< the linear system is singular (rays parallel, or numerically so)
  kBehindCamera,       ///< the point's depth is <= min_depth_m in some camera
  kLargeReprojection,  ///< reprojection RMS above max_reprojection_rms_px
};
const char* ToString(TriangulationStatus status);

struct TriangulationConfig {
  /// Smallest parallax [deg]. At 1 deg the depth's relative error is ~ (pixel noise / f) / parallax: 0.5 px at
  /// 460 px gives ~6 %; below, the depth is too weak to help the estimator.
  double min_parallax_deg = 1.0;
  /// Largest reprojection RMS [px] over all observations. 2 px = 4 sigma of the 0.5 px noise of a KLT feature
  /// tracker; a mismatched track gives more.
  double max_reprojection_rms_px = 2.0;
  /// Focal length used only to express the normalised-plane error in pixels [px] (calib.hpp's default camera).
  double focal_length_px = 462.0;
  /// The point must lie at least this far in front of every camera (z) [m]. 0.1 m: nearer than any lens focuses.
  double min_depth_m = 0.1;
  /// Gauss-Newton steps after the midpoint. 10: it converges in 2-4 (a 3-parameter problem from a close start).
  int max_iterations = 10;

  bool Validate(std::string* error) const;
};

struct Triangulation {
  bool valid = false;  ///< status == kValid
  TriangulationStatus status = TriangulationStatus::kInvalidInput;
  Eigen::Vector3d point_world = Eigen::Vector3d::Zero();  ///< [m]; filled when the solve ran, also when rejected
  double depth_anchor_m = 0.0;        ///< z of the point in the first (anchor) camera [m]
  double parallax_rad = 0.0;          ///< largest angle between two observation rays [rad]
  double reprojection_rms_px = 0.0;   ///< RMS of the normalised-plane residuals times focal_length_px [px]
  int iterations = 0;                 ///< Gauss-Newton steps taken
};

/// Triangulates one feature from its normalised coordinates xy_normalised[k] seen by cameras T_world_cam[k]
/// (T_world_cam[0] is the anchor).
Triangulation TriangulateFeature(const std::vector<Eigen::Vector2d>& xy_normalised,
                                 const std::vector<Pose3>& T_world_cam, const TriangulationConfig& config = {});

}  // namespace rotolidar::visual
