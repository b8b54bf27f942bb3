#pragma once
// Moving objects that travel with the rig, out of registration. The arrival test (FreeSpaceFilter::
// SeenThroughBefore) drops a scan feature that stands where earlier scans saw free space. An object moving away
// from the rig along its line of sight (a person walking ahead in the same direction, a car ahead in traffic) is
// never an arrival: the rays that passed its present place a moment ago ended on its own earlier body. Seen from
// the rig it stands still, so its points pull the pose along with it, and in a corridor, where little else fixes
// the axis, they win: busy corridor, 20 s, typical, seed 1, the velocity estimate decays from 1.2 to -0.5 m/s.
//
// Its trail shows the other way round: the present scan sees through the places the object's points held a few
// scans ago. VacatedScreen judges the recent scans' features (at their registered poses) with the present scan's
// range image (at the predicted pose); those it sees through are vacated, and the present scan's features within
// vacated_radius_m of a vacated point are taken for the object that left it and are dropped before registration. This is
// the "later" half of the free-space test (Kim & Kim, "Remove, then Revert", IROS 2020) run on the last fraction
// of a second, so that an object is caught while it is still in view; the radius spans what the object moved since
// (walking at 1.3 m/s for 0.15-0.6 s: 0.2-0.8 m) plus its body's depth.
//
// Safety valve: a prediction that is off along the line of sight makes static surfaces look vacated (the same
// failure the arrival test has). When more than vacated_max_share of the features are flagged nothing is dropped,
// and the result says so.
//
// Frames: features in the base frame of their scan; poses T_world_base; world [m]. The image is the present scan's
// (FreeSpaceFilter::PrepareImage), about the sensor origin in the base frame. Thread safety: none.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

#include <Eigen/Core>

#include "core/pipeline/free_space.hpp"
#include "core/types/geometry.hpp"
#include "core/types/time.hpp"

namespace rotolidar {

/// What one Flag call found.
struct VacatedResult {
  size_t vacated = 0;     ///< recent features the present scan saw through
  size_t flagged = 0;     ///< present features within the radius of one of them
  bool valve = false;     ///< flagged exceeded max_share of the features: none are marked
};

class VacatedScreen {
 public:
  /// Uses config's vacated_* fields, margins, bins_per_face and min_looked_bins; config must Validate.
  /// origin_base: the sensor origin in the base frame [m] (the images' origin).
  VacatedScreen(const FreeSpaceConfig& config, const Eigen::Vector3d& origin_base);

  /// The present scan at t_s [s]: its range image (FreeSpaceFilter::PrepareImage, base frame about the sensor
  /// origin), its features (3xN, base frame) and the predicted T_world_base. (*flagged)[i] = 1 for the features
  /// to drop, else 0 (resized to N; all 0 when the valve opened or nothing was vacated).
  VacatedResult Flag(Seconds t_s, const Pose3& T_world_base_guess, const RangeImage& image,
                     const Eigen::Matrix3Xf& features_base, std::vector<uint8_t>* flagged) const;
  /// The scan's features (all of them, before any screen; base frame) at its registered pose, kept for the scans
  /// of the next vacated_max_age_s. Call after Flag for the same scan.
  void Remember(Seconds t_s, const Pose3& T_world_base, const Eigen::Matrix3Xf& features_base);

 private:
  struct Recent {
    Seconds t_s;
    Eigen::Matrix3Xf p_world;  ///< one feature per column [m]
  };
  /// The recent features (aged min..max) the image placed at T_world_base sees through, as xyz triples.
  void Vacated(Seconds t_s, const Pose3& T_world_base, const RangeImage& image, std::vector<float>* xyz) const;

  FreeSpaceConfig config_;
  Eigen::Vector3f origin_base_;
  std::deque<Recent> recent_;  ///< time order
};

}  // namespace rotolidar
