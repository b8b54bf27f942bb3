#pragma once
// A small plotting library that writes standalone SVG documents as strings (no Python, no external tool):
// line plots (several series, legend, error bars), scatter plots, histograms and grouped bar charts, each with
// linear or log10 axes, "nice" ticks and labelled units. Top views of point clouds coloured by a scalar live
// in bench/report/svg_raster.hpp and share PlotOptions.
//
// Contract: every function returns one complete `<svg xmlns=...>...</svg>` element (valid XML, text escaped),
// `width_px` x `height_px` in size, usable as a file or inlined into HTML. Non-finite values are skipped (a line
// is broken at them); on a log axis non-positive values are skipped too. Empty input gives an empty frame
// with a "no data" note, never a failure. Pure functions: no state, no randomness, thread-safe.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace rotolidar::bench {

/// Colour of series `index` in the default palette (matplotlib's tab10, cycled), as "#rrggbb".
std::string PaletteColor(size_t index);

/// One curve (or set of markers) in a line or scatter plot.
struct PlotSeries {
  std::string label;          ///< legend entry; empty = left out of the legend
  std::vector<double> x, y;   ///< equal sizes (the shorter length is used otherwise)
  std::vector<double> y_err;  ///< optional symmetric error bars, same size as y; empty = none
  std::string color;          ///< CSS colour ("#1f77b4", "red"); empty = PaletteColor(series index)
  bool line = true;           ///< connect consecutive finite points
  bool markers = false;       ///< a circle at each point
  bool dashed = false;
  double line_width_px = 1.5;
  double marker_radius_px = 2.5;
};

/// A horizontal or vertical reference line (threshold, median, RMSE ...), drawn dashed with its label.
struct RefLine {
  double value = 0.0;  ///< in data units of its axis
  std::string label;
  std::string color = "#555555";
};

/// A shaded stretch of the x axis (e.g. scans whose registration failed), translucent over the plot area.
struct XSpan {
  double x0 = 0.0, x1 = 0.0;  ///< in data units, x0 <= x1
  std::string color = "#d62728";
};

struct PlotOptions {
  std::string title;
  std::string x_label;  ///< with the unit, e.g. "time [s]"
  std::string y_label;  ///< with the unit, e.g. "APE [m]"
  int width_px = 640;
  int height_px = 400;
  /// One data unit on x is as long as one on y (top views in metres); the shorter range is widened.
  bool equal_aspect = false;
  bool legend = true;
  bool grid = true;
  bool log_x = false;  ///< log10 axis (line / scatter plots)
  bool log_y = false;  ///< log10 axis (line / scatter / bar plots)
  /// Fixed limits; NaN = from the data (with a small margin).
  double x_min = std::numeric_limits<double>::quiet_NaN();
  double x_max = std::numeric_limits<double>::quiet_NaN();
  double y_min = std::numeric_limits<double>::quiet_NaN();
  double y_max = std::numeric_limits<double>::quiet_NaN();
  bool y_include_zero = false;  ///< extend the automatic y range to 0 (ignored on a log axis)
  std::vector<RefLine> vlines;  ///< vertical reference lines at x = value
  std::vector<RefLine> hlines;  ///< horizontal reference lines at y = value
  std::vector<XSpan> xspans;    ///< shaded x stretches (clipped to the plot; linear x only)
  /// Legend in one row above the plot area (never covers data) instead of inside its top-right corner.
  bool legend_above = false;
};

/// Line plot of `series` (each drawn per its line/markers flags).
std::string LinePlotSvg(const std::vector<PlotSeries>& series, const PlotOptions& options);

/// Scatter plot: like LinePlotSvg with markers on and lines off for every series.
std::string ScatterPlotSvg(const std::vector<PlotSeries>& series, const PlotOptions& options);

struct HistogramOptions {
  int bins = 30;  ///< >= 1
  /// Bin range; NaN = the data's min / max.
  double min = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();
  std::string color;  ///< empty = PaletteColor(0)
};

/// Histogram of `values` (counts per bin; values outside [min, max] are left out and their number is noted
/// in the plot). The y label defaults to "count" when options.y_label is empty.
std::string HistogramSvg(const std::vector<double>& values, const HistogramOptions& histogram,
                         const PlotOptions& options);

/// One group member of a bar chart: one value per category.
struct BarSeries {
  std::string label;            ///< legend entry
  std::vector<double> values;   ///< one per category; NaN = no bar
  std::vector<double> errors;   ///< optional symmetric error bars, one per category; empty = none
  std::string color;            ///< empty = PaletteColor(series index)
};

/// Grouped vertical bar chart: categories along x (their names as tick labels, slanted when long), one bar per
/// series in each category. Bars start at 0 (at the axis minimum on a log axis).
std::string BarChartSvg(const std::vector<std::string>& categories, const std::vector<BarSeries>& series,
                        const PlotOptions& options);

/// `text` with &, <, >, " and ' replaced by XML entities (for SVG and HTML).
std::string XmlEscape(const std::string& text);

}  // namespace rotolidar::bench
