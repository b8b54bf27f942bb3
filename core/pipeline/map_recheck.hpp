#pragma once
// The free-space test after the fact. A point enters the dense map once the scans around it (FreeSpaceFilter's
// delay and window, 2.5 s each way) did not see through it. What they could not judge stays: an object that stood
// still for longer than the window, or a spot the rotary rig did not look at again in time (it looks along one
// direction twice per rotor turn, and the 3x3 test often answers "unknown" at a moving person's edge). MapRecheck
// keeps judging the map's newest points with every later scan for recheck_s after they entered, and takes a point
// out once recheck_min_through scans in a row saw through it with no scan hitting it between: the object left.
// This is the "revert" half of Removert (Kim & Kim, IROS 2020) and the map maintenance of Pomerleau et al. (ICRA
// 2014) run online over a sliding time window, so its cost per scan is bounded by the map's growth over that
// window, not by the map's size.
//
// Ownership: holds copies of the tracked points (float, world) and their map indices; removes nothing itself
// (Vote returns the indices, the owner of the map removes them). Thread safety: none.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include <Eigen/Core>

#include "core/pipeline/free_space.hpp"
#include "core/pipeline/voxel_map.hpp"
#include "core/types/time.hpp"

namespace rotolidar {

class MapRecheck {
 public:
  /// Uses config's recheck_s, recheck_min_through, vote_every_scans and margins; config must Validate.
  explicit MapRecheck(const FreeSpaceConfig& config);
  /// The points `index` (from VoxelMap::Add's `kept`) entered `map` at t_s [s]: track them.
  void Track(Seconds t_s, const VoxelMap& map, const std::vector<size_t>& index);
  /// A new scan at t_s [s] with its placed image (FreeSpaceFilter::Newest): every vote_every_scans-th call it
  /// votes on the tracked points, and the map indices of those now seen through recheck_min_through times in a
  /// row are appended to *remove (each once). Points tracked for longer than recheck_s are forgotten first.
  void Vote(Seconds t_s, const PlacedImage& image, std::vector<size_t>* remove);
  size_t tracked() const { return tracked_; }  ///< points being judged

 private:
  /// The points one call of Track handed over.
  struct Batch {
    Seconds t_s;
    Eigen::Matrix3Xf p_world;  ///< one point per column [m]
    std::vector<size_t> index;  ///< map indices
    std::vector<uint8_t> run;  ///< scans in a row that saw through the point since its last hit; 255 = removed
  };
  static constexpr uint8_t kRemoved = 255;
  FreeSpaceConfig config_;
  std::deque<Batch> batches_;  ///< time order
  size_t tracked_ = 0;
  size_t calls_ = 0;
};

}  // namespace rotolidar
