#pragma once
// A yaw-invariant LiDAR place descriptor for loop closure: Scan Context (G. Kim, A. Kim, "Scan Context: Egocentric
// Spatial Descriptor for Place Recognition within 3D Point Cloud Map", IROS 2018) computed in a gravity-aligned,
// keyframe-centred frame. Stage 2 of the two-stage loop closure (LV-SLAM, Sensors 2025) checks this descriptor's
// distance between a query keyframe and a candidate; without a camera the ring key is also the retrieval key.
//
// The descriptor is a rings x sectors polar grid on the horizontal plane around the keyframe origin: ring i holds
// the horizontal ranges [i, i+1) * max_radius_m / num_rings, sector j the azimuths [-pi + j w, -pi + (j+1) w),
// w = 2 pi / num_sectors. A yaw of the sensor shifts the columns (sectors) cyclically and changes nothing else, so
//  - the ring key (the share of occupied cells of each ring) is invariant to yaw (exactly for whole-sector
//    rotations),
//  - the full distance is the minimum over the cyclic column shifts, and the best shift gives the yaw between the
//    two keyframes (resolution: one sector, 6 deg by default), the initial guess of the ICP verification.
// Roll and pitch are NOT searched: the caller levels the points first (gravity-aligned frame, z up, origin at the
// sensor). That is what the seed's criticism of Scan Context (no rotation invariance) asks for on a rig whose
// sensor tilts: the IMU's gravity removes roll/pitch, the column search removes yaw.
//
// Cell value, and why the default differs from the paper: the paper stores the maximum point height per bin. A
// rotary rig sees the full sphere, so indoors (the default 40 m radius is chosen for halls and corridors rather
// than KITTI's 80 m streets) every bin inside a room contains the ceiling and the max height is the ceiling height
// almost everywhere: the descriptor reduces to the room's footprint and loses pillars, shelves and furniture. The
// default cell value is therefore the share of occupied height bands (num_height_bands equal bands between
// min_z_m and max_z_m), a 3D occupancy column squeezed into one number: floor + ceiling = 2 bands, a pillar or wall
// = all bands, a table = floor + table top. It stays a scalar matrix, so the paper's column cosine distance, ring
// key and shift search apply unchanged, at the same cost. Measured on ray-cast synthetic scenes (tests): on a
// street both retrieve 50 / 50 revisits with their yaw; in a hall whose walls and pillars are point-symmetric the
// bands retrieve 54 / 54 with their yaw, the max height 52 / 54 with 4 yaws wrong. The price: a band is 1 m, so a
// sensor height change between visits that moves a surface across a band boundary changes cells (the max height
// varies smoothly). The paper's max height is kept as an option (CellValue::kMaxHeight).
//
// Cost: ComputeLidarDescriptor is one pass over the points (an atan2 and a few compares per point); a full-shift
// DescriptorDistance is num_sectors^2 * num_rings multiply-adds (72 k for 20 x 60); the tests print timings.
// Memory: (num_rings * num_sectors + num_rings + num_sectors) floats per descriptor = 5.12 kB for 20 x 60.
// Thread safety: free functions, no shared state; LidarPlaceIndex: see the class.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "core/util/status.hpp"

namespace rotolidar::loop {

struct LidarDescriptorConfig {
  /// What a cell stores (see the file comment).
  enum class CellValue {
    kHeightBands,  ///< share of occupied height bands in (0, 1]: 3D occupancy, robust to ceilings (default)
    kMaxHeight,    ///< Scan Context's max height above min_z_m [m], in (0, max_z_m - min_z_m]
  };
  int num_rings = 20;        ///< radial bins (paper: 20)
  int num_sectors = 60;      ///< azimuth bins (paper: 60, i.e. 6 deg; the yaw resolution)
  double max_radius_m = 40;  ///< horizontal range covered; farther points are ignored. 40 m: indoor halls and
                             ///< campus streets; the paper's 80 m suits cars on open roads
  double min_z_m = -2.5;     ///< points below this height (keyframe frame, sensor at 0) are ignored: below the floor
  double max_z_m = 5.5;      ///< points above are ignored: keeps tall far structure from dominating
  CellValue cell_value = CellValue::kHeightBands;
  int num_height_bands = 8;  ///< kHeightBands only: bands of (max_z_m - min_z_m) / num_height_bands (1 m default)
  bool Validate(std::string* error) const;
};

/// One keyframe's descriptor. An empty cloud (or one with no point inside the radius and height limits) gives an
/// all-zero matrix and num_points == 0; its distance to any descriptor is 1 (DescriptorDistance).
struct LidarDescriptor {
  Eigen::MatrixXf cells;      ///< num_rings x num_sectors; 0 = empty bin, > 0 = occupied (see CellValue)
  Eigen::VectorXf ring_key;   ///< num_rings: share of each ring's cells that are occupied, in [0, 1] (yaw-invariant)
  Eigen::VectorXf sector_key; ///< num_sectors: mean of each sector's cells over the rings (shifts with yaw)
  size_t num_points = 0;      ///< points that fell inside the grid and the height limits
  int num_rings() const { return int(cells.rows()); }
  int num_sectors() const { return int(cells.cols()); }
};

/// Computes the descriptor of points given in the gravity-aligned keyframe frame (z up, origin at the sensor) [m].
/// Points outside max_radius_m (horizontal range), outside [min_z_m, max_z_m] or not finite are skipped. The
/// config must be valid (Validate); an invalid one yields an empty 0 x 0 descriptor.
LidarDescriptor ComputeLidarDescriptor(const std::vector<Eigen::Vector3f>& points, const LidarDescriptorConfig& config);
LidarDescriptor ComputeLidarDescriptor(const pcl::PointCloud<pcl::PointXYZ>& points,
                                       const LidarDescriptorConfig& config);

/// Result of comparing two descriptors a (query) and b (candidate).
struct DescriptorMatch {
  /// Scan Context distance at the best shift: the mean over columns of (1 - cosine similarity), in [0, 1]. Columns
  /// empty in both are skipped; a column empty in only one counts 1 (the paper's code skips those as well; counting
  /// them keeps a sparse scan from matching anything). 1 when nothing is comparable (empty descriptors, sizes
  /// that differ).
  double distance = 1.0;
  /// Column j of a matches column (j + best_shift) mod num_sectors of b; in [0, num_sectors).
  int best_shift = 0;
  /// Yaw of T_b_a [rad] in (-pi, pi]: a direction at azimuth theta in a's frame is at theta + yaw_rad in b's frame.
  /// RotZ(yaw_rad) is the rotation part of an initial guess of T_b_a (resolution: one sector).
  double yaw_rad = 0.0;
};

/// Shift search strategy of DescriptorDistance.
struct ShiftSearch {
  /// < 0: full search over all num_sectors shifts. >= 0: coarse-to-fine as in the paper's fast alignment: the shift
  /// that best aligns the sector keys (L2), then the full distance only for shifts within +- refine_radius_sectors.
  int refine_radius_sectors = -1;
};

/// Scan Context distance between a and b, minimised over cyclic column shifts. Different sizes give distance 1.
DescriptorMatch DescriptorDistance(const LidarDescriptor& a, const LidarDescriptor& b,
                                   const ShiftSearch& search = ShiftSearch{});

/// Euclidean distance of the ring keys (the retrieval distance). Different sizes give +infinity.
double RingKeyDistance(const LidarDescriptor& a, const LidarDescriptor& b);

struct LidarPlaceIndexConfig {
  /// Memory bound: Add fails once this many keyframes are stored (about 5.3 kB each with 20 x 60 cells, see
  /// LidarPlaceIndex::BytesPerKeyframe; 20000 keyframes, e.g. 20 km at one keyframe per metre, ~ 106 MB).
  size_t max_keyframes = 20000;
  /// Keyframes nearest in ring key that are re-ranked by the full distance (the paper's candidates: 10).
  int num_key_candidates = 10;
  ShiftSearch shift_search;  ///< shift search of the re-ranking (full search by default: it is cheap)
  bool Validate(std::string* error) const;
};

/// What to look for; the defaults exclude nothing and return the single best candidate within max_distance.
struct PlaceQuery {
  double t_s = std::numeric_limits<double>::infinity();  ///< the query keyframe's time [s]
  double exclude_recent_s = 0.0;  ///< keyframes with t_s > query t_s - exclude_recent_s are skipped (own trail)
  std::vector<int64_t> exclude_ids;  ///< keyframes skipped by id (e.g. the query's neighbours in the graph)
  int num_results = 1;               ///< at most this many candidates are returned
  /// Candidates whose full distance exceeds this are dropped. 0.35: true revisits (0.5 m away, any yaw) measured up
  /// to 0.28 on synthetic streets and halls, places 20 m down a street >= 0.4; but inside one hall other places
  /// came as close as 0.11, so the descriptor only proposes: the geometric verification decides.
  double max_distance = 0.35;
};

/// One retrieved keyframe.
struct PlaceCandidate {
  int64_t keyframe_id = -1;
  double t_s = 0.0;                ///< the stored keyframe's time [s]
  double ring_key_distance = 0.0;  ///< RingKeyDistance(query, stored)
  DescriptorMatch match;           ///< DescriptorDistance(query, stored): yaw_rad is the yaw of T_stored_query
};

/// The keyframes' descriptors, searched by ring key (brute force: a 20-float L2 per keyframe, well under a
/// millisecond for thousands of keyframes, no tree to rebuild on Add) and re-ranked by the full distance.
/// Thread safety: Query and Find are const and may run concurrently; Add must not run concurrently with anything.
class LidarPlaceIndex {
 public:
  explicit LidarPlaceIndex(const LidarPlaceIndexConfig& config = {});

  /// Stores a copy of `descriptor` under `keyframe_id` (time t_s [s]). Errors (nothing stored): invalid config,
  /// duplicate id, index full (max_keyframes), a 0 x 0 descriptor or one whose size differs from the first stored.
  Status Add(int64_t keyframe_id, double t_s, const LidarDescriptor& descriptor);

  /// The best candidates for `query`: the num_key_candidates nearest non-excluded keyframes by ring key, re-ranked
  /// by DescriptorDistance (ascending), filtered by max_distance, at most num_results. Empty when nothing qualifies
  /// (an empty index, all excluded, a query of another size).
  std::vector<PlaceCandidate> Query(const LidarDescriptor& query, const PlaceQuery& options) const;

  /// The stored descriptor of a keyframe, or nullptr. Valid until the next Add.
  const LidarDescriptor* Find(int64_t keyframe_id) const;
  size_t size() const { return entries_.size(); }
  /// Approximate heap + bookkeeping bytes of one stored keyframe for a descriptor of this size.
  static size_t BytesPerKeyframe(int num_rings, int num_sectors);

 private:
  struct Entry {
    int64_t keyframe_id;
    double t_s;
    LidarDescriptor descriptor;
  };
  LidarPlaceIndexConfig config_;
  std::vector<Entry> entries_;
  std::unordered_map<int64_t, size_t> slot_of_id_;
};

}  // namespace rotolidar::loop
