#include "bench/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>

#include "bench/report/svg_axes.hpp"

namespace rotolidar::bench {
namespace {

using svg::Canvas;
using svg::FinalizeRange;
using svg::LegendEntry;
using svg::Px;
using svg::Range;

std::string SeriesColor(const std::string& color, size_t index) { return color.empty() ? PaletteColor(index) : color; }

}  // namespace

std::string PaletteColor(size_t index) {
  static const char* kTab10[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                 "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  return kTab10[index % 10];
}

std::string XmlEscape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string LinePlotSvg(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  Range xr, yr;
  bool any = false;
  for (const PlotSeries& s : series) {
    const size_t n = std::min(s.x.size(), s.y.size());
    for (size_t i = 0; i < n; ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      if ((options.log_x && s.x[i] <= 0) || (options.log_y && s.y[i] <= 0)) continue;
      xr.Add(s.x[i], options.log_x);
      yr.Add(s.y[i], options.log_y);
      any = true;
      if (s.y_err.size() >= n && std::isfinite(s.y_err[i])) {
        yr.Add(s.y[i] - s.y_err[i], options.log_y);
        yr.Add(s.y[i] + s.y_err[i], options.log_y);
      }
    }
  }
  for (const RefLine& l : options.hlines) yr.Add(l.value, options.log_y);
  FinalizeRange(&xr, options.x_min, options.x_max, false, options.log_x, true);
  FinalizeRange(&yr, options.y_min, options.y_max, options.y_include_zero, options.log_y, true);
  Canvas canvas(options);
  canvas.SetRanges(xr, yr);
  canvas.DrawFrame();
  std::vector<LegendEntry> legend;
  for (size_t k = 0; k < series.size(); ++k) {
    const std::string color = SeriesColor(series[k].color, k);
    canvas.DrawSeries(series[k], color);
    legend.push_back({series[k].label, color, series[k].line, series[k].markers, false, series[k].dashed});
  }
  if (!any) canvas.NoData();
  canvas.DrawRefLines();
  canvas.DrawLegend(legend);
  return canvas.Finish();
}

std::string ScatterPlotSvg(const std::vector<PlotSeries>& series, const PlotOptions& options) {
  std::vector<PlotSeries> copy = series;
  for (PlotSeries& s : copy) s.line = false, s.markers = true;
  return LinePlotSvg(copy, options);
}

std::string HistogramSvg(const std::vector<double>& values, const HistogramOptions& histogram,
                         const PlotOptions& options) {
  Range data;
  for (double v : values) data.Add(v, false);
  double lo = std::isfinite(histogram.min) ? histogram.min : (data.valid ? data.lo : 0.0);
  double hi = std::isfinite(histogram.max) ? histogram.max : (data.valid ? data.hi : 1.0);
  if (hi <= lo) hi = lo + 1.0;
  const int bins = std::max(1, histogram.bins);
  std::vector<size_t> counts(size_t(bins), 0);
  size_t outside = 0;
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    if (v < lo || v > hi) {
      ++outside;
      continue;
    }
    counts[std::min(size_t(bins) - 1, size_t((v - lo) / (hi - lo) * bins))]++;
  }
  PlotOptions o = options;
  o.log_x = o.log_y = false;
  o.equal_aspect = false;
  if (o.y_label.empty()) o.y_label = "count";
  Range xr{lo, hi, true}, yr{0.0, 1.0, true};
  for (size_t c : counts) yr.Add(double(c), false);
  FinalizeRange(&xr, o.x_min, o.x_max, false, false, false);
  FinalizeRange(&yr, o.y_min, o.y_max, true, false, true);
  Canvas canvas(o);
  canvas.SetRanges(xr, yr);
  canvas.DrawFrame();
  const std::string color = SeriesColor(histogram.color, 0);
  std::ostringstream& b = canvas.body();
  b << "<g class=\"bars\" clip-path=\"url(#@CLIP@)\" fill=\"" << color << "\" stroke=\"white\" stroke-width=\"0.5\">\n";
  const double w = (hi - lo) / bins;
  for (int i = 0; i < bins; ++i) {
    if (counts[size_t(i)] == 0) continue;
    const double x0 = canvas.X(lo + i * w), x1 = canvas.X(lo + (i + 1) * w), y = canvas.Y(double(counts[size_t(i)]));
    b << "<rect x=\"" << Px(x0) << "\" y=\"" << Px(y) << "\" width=\"" << Px(x1 - x0) << "\" height=\""
      << Px(canvas.Y(0.0) - y) << "\"/>\n";
  }
  b << "</g>\n";
  if (!data.valid) canvas.NoData();
  if (outside > 0)
    b << "<text x=\"" << Px(canvas.plot_left() + canvas.plot_width() - 6) << "\" y=\"" << Px(canvas.plot_top() + 38)
      << "\" font-size=\"10\" fill=\"#555\" text-anchor=\"end\">" << outside << " values outside the range</text>\n";
  canvas.DrawRefLines();
  return canvas.Finish();
}

std::string BarChartSvg(const std::vector<std::string>& categories, const std::vector<BarSeries>& series,
                        const PlotOptions& options) {
  PlotOptions o = options;
  o.log_x = false;
  o.equal_aspect = false;
  const size_t n = categories.size();
  Range xr{-0.5, std::max(0.5, double(n) - 0.5), true}, yr;
  bool any = false;
  for (const BarSeries& s : series)
    for (size_t i = 0; i < std::min(n, s.values.size()); ++i) {
      if (!std::isfinite(s.values[i])) continue;
      any = true;
      yr.Add(s.values[i], o.log_y);
      if (i < s.errors.size() && std::isfinite(s.errors[i])) yr.Add(s.values[i] + s.errors[i], o.log_y);
    }
  for (const RefLine& l : o.hlines) yr.Add(l.value, o.log_y);
  FinalizeRange(&yr, o.y_min, o.y_max, true, o.log_y, true);
  Canvas canvas(o);
  canvas.SetRanges(xr, yr);
  canvas.DrawFrame(categories);
  const double group_w = 0.8, bar_w = group_w / double(std::max<size_t>(1, series.size()));
  const double base = o.log_y ? yr.lo : 0.0;
  std::ostringstream& b = canvas.body();
  std::vector<LegendEntry> legend;
  for (size_t k = 0; k < series.size(); ++k) {
    const BarSeries& s = series[k];
    const std::string color = SeriesColor(s.color, k);
    legend.push_back({s.label, color, false, false, true, false});
    b << "<g class=\"bars\" clip-path=\"url(#@CLIP@)\" fill=\"" << color << "\">\n";
    for (size_t i = 0; i < std::min(n, s.values.size()); ++i) {
      if (!canvas.InY(s.values[i])) continue;
      const double c = double(i) - group_w / 2 + (double(k) + 0.5) * bar_w;
      const double x0 = canvas.X(c - bar_w / 2 * 0.9), x1 = canvas.X(c + bar_w / 2 * 0.9);
      const double y = canvas.Y(s.values[i]), y0 = canvas.Y(base);
      b << "<rect x=\"" << Px(x0) << "\" y=\"" << Px(std::min(y, y0)) << "\" width=\"" << Px(x1 - x0)
        << "\" height=\"" << Px(std::abs(y0 - y)) << "\"/>\n";
      if (i < s.errors.size() && std::isfinite(s.errors[i]) && canvas.InY(s.values[i] - s.errors[i])) {
        const double ya = canvas.Y(s.values[i] - s.errors[i]), yb = canvas.Y(s.values[i] + s.errors[i]);
        const double px = canvas.X(c);
        b << "<path d=\"M" << Px(px) << " " << Px(ya) << "V" << Px(yb) << "M" << Px(px - 3) << " " << Px(ya)
          << "h6M" << Px(px - 3) << " " << Px(yb) << "h6\" stroke=\"#222\" fill=\"none\"/>\n";
      }
    }
    b << "</g>\n";
  }
  if (!any) canvas.NoData();
  canvas.DrawRefLines();
  canvas.DrawLegend(legend);
  return canvas.Finish();
}

}  // namespace rotolidar::bench
