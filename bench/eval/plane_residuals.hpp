#pragma once
// Range noise as seen on flat surfaces: per-point residuals of VLP-16 returns to planes found by RANSAC, binned by
// range and incidence angle. The same measure runs on real captures and on the twin, so that the twin's noise
// model can be fitted to the real sensor (docs/lidar_model.md, section 5).
//
// Method, per revolution (points in the lidar frame; the head must not move during a revolution: a static sensor
// or a stopped rig): up to max_planes times, PCL's RANSAC plane segmentation (pcl::SACSegmentation, distance
// threshold ransac_threshold_m) finds the largest plane among the points left; the plane is refitted by least
// squares (PCA) to those inliers, its points are those within ransac_threshold_m of the refit, and each one's
// residual is its signed distance to it. Planes with fewer than min_plane_points points end the search; planes
// passing within min_plane_offset_m of the sensor are removed unmeasured. A
// point's incidence is the angle between its ray (from the lidar origin) and the plane normal.
// Residuals are truncated at +-ransac_threshold_m by construction: compare only results of equal options.
// PCL's RANSAC is seeded with a fixed value, so results are deterministic.
#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct PlaneResidualOptions {
  double min_range_m = 1.0;   ///< points outside [min, max] are not used
  double max_range_m = 60.0;
  double ransac_threshold_m = 0.10;  ///< RANSAC inlier band and the residual window [m]
  int max_planes = 8;                ///< planes per revolution
  int min_plane_points = 400;        ///< smaller planes are not used (and end the search)
  int ransac_iterations = 400;
  /// Planes closer than this to the sensor are dropped (their points removed, not measured): a plane through the
  /// sensor is a bundle of scan lines (RANSAC finds those among clutter), not a surface seen by the beams.
  double min_plane_offset_m = 0.3;
  std::vector<double> range_edges_m = {1, 2, 4, 6, 8, 12, 16, 25, 40, 60};  ///< bin edges, increasing
  std::vector<double> incidence_edges_deg = {0, 20, 40, 60, 75, 90};      ///< bin edges, increasing
  bool Validate(std::string* error) const;
};

/// One point on a fitted plane.
struct PlaneResidual {
  float range_m = 0.f;
  float incidence_deg = 0.f;
  float residual_m = 0.f;  ///< signed distance to the plane (along its normal, towards the sensor positive)
  float intensity = 0.f;   ///< reflectivity byte
  int scan = 0;            ///< revolution index
  int plane = 0;           ///< plane index within the revolution
};

/// Statistics of |residual| over one bin.
struct ResidualBin {
  double lo = 0.0, hi = 0.0;  ///< bin edges (range [m] or incidence [deg])
  std::size_t count = 0;
  double median_abs_m = 0.0;
  double p90_abs_m = 0.0;
  double std_m = 0.0;  ///< standard deviation of the signed residuals
};

struct PlaneResidualResult {
  std::vector<PlaneResidual> points;
  std::vector<ResidualBin> by_range, by_incidence;
  ResidualBin all;
  int scans = 0;   ///< revolutions used
  int planes = 0;  ///< planes found over all revolutions
};

/// Decoded revolutions of `input`: a file of concatenated 1206-byte VLP-16 payloads (name ending in .bin), a
/// pcap, or a recording folder (its lidar.pcap and calib.yaml's intrinsics). Only full revolutions (cut at
/// azimuth 0) are kept. Fails naming the input when it cannot be read or holds no full revolution.
Status LoadLidarRevolutions(const std::string& input, std::vector<LidarScan>* scans);

/// Revolutions from decoded packets (the common part of LoadLidarRevolutions, also used for the twin).
Status RevolutionsFromPackets(const std::vector<LidarPacket>& packets, const LidarIntrinsics& intrinsics,
                              std::vector<LidarScan>* scans);

/// The measure described in the file comment. Fails on invalid options or when no plane was found.
Status MeasurePlaneResiduals(const std::vector<LidarScan>& scans, const PlaneResidualOptions& options,
                             PlaneResidualResult* result);

/// |residual| statistics of the points whose key (range or incidence) falls in each [edge_i, edge_i+1).
std::vector<ResidualBin> BinResiduals(const std::vector<PlaneResidual>& points, const std::vector<double>& edges,
                                      bool by_incidence);

/// CSV: range_m,incidence_deg,residual_m,intensity,scan,plane (one row per point).
Status WritePlaneResidualCsv(const std::string& path, const PlaneResidualResult& result);
/// The bin tables (count, median, p90, std per range / incidence bin) as text.
void PrintPlaneResiduals(const PlaneResidualResult& result, std::ostream& os);

}  // namespace rotolidar::bench
