#pragma once
// Dimensions of the scene's annotated elements (doors, windows, columns) measured from a map and compared
// with their truth (sim::AnnotatedElement); docs/metrics.md "Element geometry" explains the method.
//
// Points are cropped around each element in its frame E (x = normal, y = along the width, z = up; scene.hpp).
// Planes are located with histogram modes refined by a median (robust to noise and stray points), never with
// raw min/max:
//   door/window: width = right jamb - left jamb (the reveal faces y = +-w/2 inside the wall thickness),
//                height = lintel underside - sill top (or the floor under a door);
//   column:      round (its primitive is a cylinder): trimmed least-squares circle, width = diameter;
//                otherwise width = distance between the faces y = +-w/2; height = ceiling - floor next to it.
// The annotation (centre, yaw, size) only places the crop and the search windows (+- search_margin_m), so a
// measurement can be off by at most about that margin.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sim/world/scene.hpp"

namespace rotolidar::bench {

struct ElementFitConfig {
  double search_margin_m = 0.3;     ///< search windows reach this far beyond the annotated extents
  double default_depth_m = 0.1;     ///< wall thickness assumed when the element states depth 0
  /// Central share of the other extents used per plane (away from corners, edges and the wall faces: a
  /// door's or window's reveal band is |x| <= band_fraction * depth / 2)
  double band_fraction = 0.5;
  double bin_m = 0.01;              ///< histogram bin for plane modes
  double refine_halfwidth_m = 0.03;  ///< points within this of a mode give the plane by their median
  int min_points = 15;              ///< per plane (or per circle) to report a measurement
  double normal_radius_m = 0.06;    ///< PCA normals: neighbours within this radius (at least the 10 nearest)
  /// A plane perpendicular to axis a uses only points with |n . a| >= this (round columns: |n_z| <= sin);
  /// keeps wall-face points that noise pushed into a reveal out of the jamb/sill/lintel planes.
  double normal_min_cos = 0.7;
  /// The peak must hold at least this many times the clutter level (median bin count) over its window.
  double prominence = 2.0;

  bool Validate(std::string* error) const;
};

struct ElementMeasurement {
  std::string name;
  std::string type;  ///< door, window, column
  bool width_measured = false;
  bool height_measured = false;
  std::string message;  ///< what was missing when a dimension was not measured
  double true_width_m = 0.0, true_height_m = 0.0;
  double width_m = 0.0, height_m = 0.0;              ///< measured (valid when *_measured)
  double width_error_m = 0.0, height_error_m = 0.0;  ///< measured - true
  size_t crop_points = 0;                            ///< map points in the element's crop box
};

struct ElementSummary {
  size_t elements = 0;
  size_t widths_measured = 0, heights_measured = 0;
  double width_rmse_m = 0.0, height_rmse_m = 0.0;
  double rmse_m = 0.0;           ///< over every measured width and height error together
  double max_abs_error_m = 0.0;
};

/// Measures one element from map points [world]. `scene` resolves the element's primitive (round column).
ElementMeasurement MeasureElement(const sim::Scene& scene, const sim::AnnotatedElement& element,
                                  const std::vector<Eigen::Vector3f>& map_world, const ElementFitConfig& config);

ElementSummary SummarizeElements(const std::vector<ElementMeasurement>& elements);

/// Robust position of a plane from coordinates along its normal: the mode of a histogram (bin_m, 3-bin
/// smoothing) over [lo, hi], refined as the median of the values within refine_halfwidth_m of the mode.
/// False when fewer than max(min_points, prominence x the clutter level) values fall within the refinement
/// window (the clutter level: the median bin count of `clutter_values`, default `values`, times the
/// window's bins). Exposed for tests.
bool PlaneOffsetByMode(const std::vector<double>& values, double lo, double hi, const ElementFitConfig& config,
                       double* offset, const std::vector<double>* clutter_values = nullptr);

}  // namespace rotolidar::bench
