#pragma once
// Cuts a time-ordered stream of decoded VLP-16 points into revolutions of the head.
#include <optional>
#include <vector>

#include "core/types/messages.hpp"

namespace rotolidar {

/// Feed points in time order (as Vlp16Decoder emits them). A scan ends where the head's azimuth crosses
/// `cut_azimuth_deg` (degrees, manual convention, any value; taken mod 360): the point's azimuth relative to the cut,
/// (azimuth - cut) mod 360, drops by more than 180 deg from one point to the next (so the 360 -> 0 wrap is handled
/// and the small back-steps of interpolation noise are not cuts). The point that crossed starts the next scan.
/// The first scan spans from the stream's start to the first crossing, so it is usually a partial revolution;
/// Flush() returns the trailing partial one. Scans are never empty. Not thread-safe.
class RevolutionSplitter {
 public:
  explicit RevolutionSplitter(double cut_azimuth_deg = 0.0);

  /// Adds one point; returns the finished scan when this point crossed the cut.
  std::optional<LidarScan> Add(const LidarPoint& point);
  /// Adds many points; appends every finished scan to *finished.
  void Add(const std::vector<LidarPoint>& points, std::vector<LidarScan>* finished);
  /// The scan in progress (nullopt when empty); the splitter starts over afterwards.
  std::optional<LidarScan> Flush();

  std::size_t crossings() const { return crossings_; }  ///< cuts seen so far

 private:
  double RelativeAzimuth(float azimuth_deg) const;
  /// Adds the point; true when it crossed the cut (the finished scan is then in finished_).
  bool Append(const LidarPoint& point);

  double cut_deg_;
  LidarScan current_;
  LidarScan finished_;
  double last_rel_deg_ = -1.0;  // < 0: no point yet
  std::size_t crossings_ = 0;
};

}  // namespace rotolidar
