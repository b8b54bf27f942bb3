#pragma once
// Internal to bench/report: the frame shared by every SVG plot — data ranges, the data-to-pixel mapping
// (linear or log10, optional equal aspect), ticks, grid, axis labels, title, legend and reference lines.
// Users call the functions of svg_plot.hpp / svg_raster.hpp instead.
#include <sstream>
#include <string>
#include <vector>

#include "bench/report/svg_plot.hpp"

namespace rotolidar::bench::svg {

/// Ticks at 1, 2, 5 x 10^k between lo and hi (about `target` of them), inclusive of the ends when they fall
/// on a tick. Empty when lo/hi are not finite or lo >= hi.
std::vector<double> NiceTicks(double lo, double hi, int target);
/// Decade ticks (and 2, 5 x 10^k when the range spans less than two decades) within [lo, hi] (both > 0).
std::vector<double> LogTicks(double lo, double hi);
/// A tick label with as many decimals as `step` needs ("0.25", "10", "1e+06").
std::string FormatTick(double value, double step);
/// printf-style number for SVG attributes (fixed, 2 decimals).
std::string Px(double v);

/// The data range of one axis, built up from values; log axes keep only positive values.
struct Range {
  double lo = 0.0, hi = 0.0;
  bool valid = false;
  void Add(double v, bool log);
};

/// Applies PlotOptions limits, include-zero and a 4 % margin (in log space on a log axis); an empty or
/// degenerate range becomes [v - 1, v + 1] (or [0, 1] when nothing was added).
void FinalizeRange(Range* range, double fixed_min, double fixed_max, bool include_zero, bool log, bool margin);

struct LegendEntry {
  std::string label;
  std::string color;
  bool line = true;
  bool marker = false;
  bool box = false;  ///< a filled square (bars, histograms)
  bool dashed = false;
};

class Canvas {
 public:
  /// `right_extra_px`: room reserved right of the plot area (a colour bar).
  Canvas(const PlotOptions& options, double right_extra_px = 0.0);

  /// Sets the data ranges (already finalized); with equal_aspect the shorter one is widened to fill.
  void SetRanges(Range x, Range y);
  double X(double v) const;  ///< data -> pixel x (log applied)
  double Y(double v) const;  ///< data -> pixel y
  bool InX(double v) const;  ///< finite and usable on the x axis (positive on a log axis)
  bool InY(double v) const;

  /// Background, grid, ticks, tick labels, axis labels, title. `x_categories` (optional) replaces numeric x
  /// ticks by one label at each integer 0..n-1.
  void DrawFrame(const std::vector<std::string>& x_categories = {});
  /// Reference lines of the options (call after the data, before the legend).
  void DrawRefLines();
  void DrawLegend(const std::vector<LegendEntry>& entries);
  void DrawSeries(const PlotSeries& series, const std::string& color);
  void NoData();

  double plot_left() const { return left_; }
  double plot_top() const { return top_; }
  double plot_width() const { return width_; }
  double plot_height() const { return height_; }
  const Range& x_range() const { return x_; }
  const Range& y_range() const { return y_; }
  std::ostringstream& body() { return body_; }
  const PlotOptions& options() const { return options_; }

  /// The complete <svg> document: header, clip path, body, footer.
  std::string Finish() const;

 private:
  void DrawXTicks(const std::vector<std::string>& x_categories);
  void DrawYTicks();
  PlotOptions options_;
  double left_ = 0.0, top_ = 0.0, width_ = 0.0, height_ = 0.0;
  Range x_, y_;
  std::ostringstream body_;
};

}  // namespace rotolidar::bench::svg
