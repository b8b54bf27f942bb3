#include "bench/report/svg_raster.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bench/report/svg_axes.hpp"

namespace rotolidar::bench {
namespace {

using svg::Px;

constexpr double kColorbarRoomPx = 86.0;

/// Control points of the colour maps (equally spaced in t), linearly interpolated.
const std::vector<std::array<double, 3>>& Stops(Colormap map) {
  static const std::vector<std::array<double, 3>> kViridis = {
      {0.267, 0.005, 0.329}, {0.283, 0.141, 0.458}, {0.254, 0.265, 0.530}, {0.207, 0.372, 0.553},
      {0.164, 0.471, 0.558}, {0.128, 0.567, 0.551}, {0.135, 0.659, 0.518}, {0.267, 0.749, 0.441},
      {0.478, 0.821, 0.318}, {0.741, 0.873, 0.150}, {0.993, 0.906, 0.144}};
  static const std::vector<std::array<double, 3>> kTurbo = {
      {0.190, 0.072, 0.232}, {0.276, 0.421, 0.891}, {0.158, 0.736, 0.923}, {0.197, 0.949, 0.595},
      {0.644, 0.990, 0.234}, {0.939, 0.826, 0.223}, {0.977, 0.503, 0.141}, {0.824, 0.210, 0.031},
      {0.480, 0.016, 0.011}};
  static const std::vector<std::array<double, 3>> kRdYlGn = {
      {0.647, 0.000, 0.149}, {0.957, 0.427, 0.263}, {0.996, 0.878, 0.545}, {0.851, 0.937, 0.545},
      {0.400, 0.741, 0.388}, {0.000, 0.408, 0.216}};
  switch (map) {
    case Colormap::kTurbo: return kTurbo;
    case Colormap::kRedYellowGreen: return kRdYlGn;
    default: return kViridis;
  }
}

/// Per-cell accumulation of point values.
struct Cells {
  int cols = 0, rows = 0;
  std::vector<double> sum, min, max;
  std::vector<int> count;
  double Value(size_t i, CellReduce reduce) const {
    switch (reduce) {
      case CellReduce::kMax: return max[i];
      case CellReduce::kMin: return min[i];
      default: return sum[i] / count[i];
    }
  }
};

/// Bins points into cells covering the canvas's visible range (row 0 = top = largest y).
Cells BinPoints(const svg::Canvas& canvas, const std::vector<Eigen::Vector2d>& xy, const std::vector<double>& v,
                const TopViewOptions& opt) {
  const svg::Range& xr = canvas.x_range();
  const svg::Range& yr = canvas.y_range();
  const double span = std::max(xr.hi - xr.lo, yr.hi - yr.lo);
  double cell = std::max(opt.cell_m, (xr.hi - xr.lo) / std::max(1.0, canvas.plot_width()));
  cell = std::max(cell, span / std::max(16, opt.max_raster_px));
  Cells c;
  c.cols = std::max(1, int(std::ceil((xr.hi - xr.lo) / cell)));
  c.rows = std::max(1, int(std::ceil((yr.hi - yr.lo) / cell)));
  const size_t n = size_t(c.cols) * size_t(c.rows);
  c.sum.assign(n, 0.0), c.min.assign(n, INFINITY), c.max.assign(n, -INFINITY), c.count.assign(n, 0);
  for (size_t i = 0; i < std::min(xy.size(), v.size()); ++i) {
    if (!xy[i].allFinite() || !std::isfinite(v[i])) continue;
    const int col = int(std::floor((xy[i].x() - xr.lo) / (xr.hi - xr.lo) * c.cols));
    const int row = int(std::floor((yr.hi - xy[i].y()) / (yr.hi - yr.lo) * c.rows));
    if (col < 0 || col >= c.cols || row < 0 || row >= c.rows) continue;
    const size_t k = size_t(row) * size_t(c.cols) + size_t(col);
    c.sum[k] += v[i], c.count[k]++;
    c.min[k] = std::min(c.min[k], v[i]), c.max[k] = std::max(c.max[k], v[i]);
  }
  return c;
}

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const size_t k = std::min(values.size() - 1, size_t(q * double(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + long(k), values.end());
  return values[k];
}

/// BGRA image of the cells (alpha 0 where empty), empty pixels filled from occupied ones within dilate_px.
cv::Mat ColorCells(const Cells& c, const TopViewOptions& opt, double vmin, double vmax) {
  cv::Mat img(c.rows, c.cols, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  for (int r = 0; r < c.rows; ++r)
    for (int q = 0; q < c.cols; ++q) {
      const size_t k = size_t(r) * size_t(c.cols) + size_t(q);
      if (c.count[k] == 0) continue;
      uint8_t R, G, B;
      ColormapRgb(opt.colormap, (c.Value(k, opt.reduce) - vmin) / (vmax - vmin), &R, &G, &B);
      img.at<cv::Vec4b>(r, q) = cv::Vec4b(B, G, R, 255);
    }
  if (opt.dilate_px <= 0) return img;
  cv::Mat out = img.clone();
  const int d = opt.dilate_px;
  for (int r = 0; r < c.rows; ++r)
    for (int q = 0; q < c.cols; ++q) {
      if (img.at<cv::Vec4b>(r, q)[3] != 0) continue;
      for (int dr = -d; dr <= d && out.at<cv::Vec4b>(r, q)[3] == 0; ++dr)
        for (int dq = -d; dq <= d; ++dq) {
          const int rr = r + dr, qq = q + dq;
          if (rr < 0 || qq < 0 || rr >= c.rows || qq >= c.cols || img.at<cv::Vec4b>(rr, qq)[3] == 0) continue;
          out.at<cv::Vec4b>(r, q) = img.at<cv::Vec4b>(rr, qq);
          break;
        }
    }
  return out;
}

void DrawColorbar(svg::Canvas* canvas, const TopViewOptions& opt, double vmin, double vmax) {
  std::ostringstream& o = canvas->body();
  const double x0 = canvas->plot_left() + canvas->plot_width() + 14, w = 14.0;
  const double top = canvas->plot_top(), h = canvas->plot_height();
  constexpr int kSteps = 64;
  o << "<g class=\"colorbar\" font-size=\"11\">\n";
  for (int i = 0; i < kSteps; ++i) {
    uint8_t r, g, b;
    ColormapRgb(opt.colormap, (i + 0.5) / kSteps, &r, &g, &b);
    char color[8];
    std::snprintf(color, sizeof(color), "#%02x%02x%02x", r, g, b);
    o << "<rect x=\"" << Px(x0) << "\" y=\"" << Px(top + h - (i + 1) * h / kSteps) << "\" width=\"" << Px(w)
      << "\" height=\"" << Px(h / kSteps + 0.5) << "\" fill=\"" << color << "\"/>\n";
  }
  o << "<rect x=\"" << Px(x0) << "\" y=\"" << Px(top) << "\" width=\"" << Px(w) << "\" height=\"" << Px(h)
    << "\" fill=\"none\" stroke=\"#333\"/>\n";
  const std::vector<double> ticks = svg::NiceTicks(vmin, vmax, std::max(3, int(h / 55)));
  for (double t : ticks) {
    const double y = top + h - (t - vmin) / (vmax - vmin) * h;
    o << "<line x1=\"" << Px(x0 + w) << "\" y1=\"" << Px(y) << "\" x2=\"" << Px(x0 + w + 4) << "\" y2=\"" << Px(y)
      << "\" stroke=\"#333\"/><text x=\"" << Px(x0 + w + 6) << "\" y=\"" << Px(y + 4) << "\">"
      << svg::FormatTick(t, ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0) << "</text>\n";
  }
  const double lx = x0 + w + 62, ly = top + h / 2;
  o << "<text class=\"colorbar-label\" x=\"" << Px(lx) << "\" y=\"" << Px(ly) << "\" text-anchor=\"middle\" "
    << "transform=\"rotate(-90 " << Px(lx) << " " << Px(ly) << ")\">" << XmlEscape(opt.colorbar_label)
    << "</text>\n</g>\n";
}

}  // namespace

void ColormapRgb(Colormap map, double t, uint8_t* r, uint8_t* g, uint8_t* b) {
  const auto& s = Stops(map);
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
  const double f = t * double(s.size() - 1);
  const size_t i = std::min(s.size() - 2, size_t(f));
  const double a = f - double(i);
  auto mix = [&](int c) { return uint8_t(std::lround(255.0 * ((1 - a) * s[i][c] + a * s[i + 1][c]))); };
  *r = mix(0), *g = mix(1), *b = mix(2);
}

std::string PointTopViewSvg(const std::vector<Eigen::Vector2d>& xy_m, const std::vector<double>& values,
                            const TopViewOptions& top_view, const PlotOptions& options,
                            const std::vector<PlotSeries>& overlays) {
  PlotOptions o = options;
  o.equal_aspect = true;
  o.log_x = o.log_y = false;
  svg::Range xr, yr;
  const size_t n = std::min(xy_m.size(), values.size());
  for (size_t i = 0; i < n; ++i)
    if (xy_m[i].allFinite() && std::isfinite(values[i])) xr.Add(xy_m[i].x(), false), yr.Add(xy_m[i].y(), false);
  for (const PlotSeries& s : overlays)
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) xr.Add(s.x[i], false), yr.Add(s.y[i], false);
  const bool any = xr.valid;
  svg::FinalizeRange(&xr, o.x_min, o.x_max, false, false, true);
  svg::FinalizeRange(&yr, o.y_min, o.y_max, false, false, true);
  svg::Canvas canvas(o, kColorbarRoomPx);
  canvas.SetRanges(xr, yr);
  canvas.DrawFrame();
  const Cells cells = BinPoints(canvas, xy_m, values, top_view);
  std::vector<double> cell_values;
  for (size_t k = 0; k < cells.count.size(); ++k)
    if (cells.count[k] > 0) cell_values.push_back(cells.Value(k, top_view.reduce));
  double vmin = std::isfinite(top_view.value_min) ? top_view.value_min : Percentile(cell_values, 0.02);
  double vmax = std::isfinite(top_view.value_max) ? top_view.value_max : Percentile(cell_values, 0.98);
  if (!(vmax > vmin)) vmax = vmin + (std::abs(vmin) > 0 ? std::abs(vmin) : 1.0);
  if (!cell_values.empty()) {
    std::vector<uint8_t> png;
    cv::imencode(".png", ColorCells(cells, top_view, vmin, vmax), png);
    // The cells tile the plot area exactly (BinPoints maps the visible range onto cols x rows).
    canvas.body() << "<image class=\"raster\" x=\"" << Px(canvas.plot_left()) << "\" y=\"" << Px(canvas.plot_top())
                  << "\" width=\"" << Px(canvas.plot_width()) << "\" height=\"" << Px(canvas.plot_height())
                  << "\" preserveAspectRatio=\"none\" style=\"image-rendering:pixelated\" "
                  << "xlink:href=\"data:image/png;base64," << Base64Encode(png) << "\"/>\n";
  }
  std::vector<svg::LegendEntry> legend;
  for (size_t k = 0; k < overlays.size(); ++k) {
    const std::string color = overlays[k].color.empty() ? PaletteColor(k) : overlays[k].color;
    canvas.DrawSeries(overlays[k], color);
    legend.push_back({overlays[k].label, color, overlays[k].line, overlays[k].markers, false, overlays[k].dashed});
  }
  if (!any) canvas.NoData();
  DrawColorbar(&canvas, top_view, vmin, vmax);
  canvas.DrawRefLines();
  canvas.DrawLegend(legend);
  return canvas.Finish();
}

std::string Base64Encode(const std::vector<uint8_t>& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t a = bytes[i], b = i + 1 < bytes.size() ? bytes[i + 1] : 0, c = i + 2 < bytes.size() ? bytes[i + 2] : 0;
    const uint32_t v = (a << 16) | (b << 8) | c;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

}  // namespace rotolidar::bench
