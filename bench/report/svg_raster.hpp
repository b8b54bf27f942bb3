#pragma once
// Top views of point clouds for reports: points binned into a raster (one cell per pixel), each cell coloured
// by a reduction (mean / max / min) of the points' scalar through a colour map, encoded as PNG with OpenCV
// (cv::imencode) and embedded as a base64 data URI inside an SVG that carries the axes (metres, equal
// aspect), a colour bar with ticks and optional line overlays (e.g. a trajectory).
//
// Contract: PointTopViewSvg returns one complete standalone `<svg>` element; empty input gives an empty frame
// with a "no data" note. Pure functions, thread-safe, no randomness.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bench/report/svg_plot.hpp"

namespace rotolidar::bench {

enum class Colormap {
  kViridis,        ///< perceptually uniform, dark blue -> yellow (errors, heights)
  kTurbo,          ///< rainbow-like, high contrast
  kRedYellowGreen, ///< 0 = red, 1 = green (coverage fractions)
};

/// Colour of t in [0, 1] (clamped) as 8-bit RGB.
void ColormapRgb(Colormap map, double t, uint8_t* r, uint8_t* g, uint8_t* b);

enum class CellReduce { kMean, kMax, kMin };

struct TopViewOptions {
  double cell_m = 0.0;      ///< raster cell edge [m]; 0 = the data extent over max_raster_px
  int max_raster_px = 700;  ///< longest raster side when cell_m is 0 (also a cap when it is not)
  CellReduce reduce = CellReduce::kMean;
  Colormap colormap = Colormap::kViridis;
  /// Colour scale limits; NaN = the 2nd / 98th percentile of the cell values.
  double value_min = std::numeric_limits<double>::quiet_NaN();
  double value_max = std::numeric_limits<double>::quiet_NaN();
  std::string colorbar_label;  ///< with the unit, e.g. "map-to-truth distance [m]"
  int dilate_px = 1;           ///< each occupied cell is drawn this many pixels wider (0 = single pixels)
};

/// Top view (x right, y up, metres) of points `xy_m` coloured by `values` (same size; non-finite values and
/// points are skipped). `overlays` are drawn over the raster as in LinePlotSvg (their x/y in metres).
/// options.equal_aspect is forced on; the x/y limits of `options` crop the view when set.
std::string PointTopViewSvg(const std::vector<Eigen::Vector2d>& xy_m, const std::vector<double>& values,
                            const TopViewOptions& top_view, const PlotOptions& options,
                            const std::vector<PlotSeries>& overlays = {});

/// Standard base64 (RFC 4648, with padding) of `bytes`.
std::string Base64Encode(const std::vector<uint8_t>& bytes);

}  // namespace rotolidar::bench
