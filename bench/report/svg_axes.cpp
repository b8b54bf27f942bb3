#include "bench/report/svg_axes.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rotolidar::bench::svg {
namespace {

constexpr double kMarginLeft = 72.0, kMarginRight = 18.0, kMarginTop = 30.0, kMarginBottom = 48.0;
constexpr double kFontPx = 12.0;

/// Deterministic id for the clip path, so several SVGs inlined into one HTML page do not collide.
std::string HashId(const std::string& text) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  char buf[32];
  std::snprintf(buf, sizeof(buf), "c%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string DashAttr(bool dashed) { return dashed ? " stroke-dasharray=\"6,4\"" : ""; }

}  // namespace

std::vector<double> NiceTicks(double lo, double hi, int target) {
  std::vector<double> ticks;
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo >= hi || target < 1) return ticks;
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;  // the 1-2-5 step nearest to the raw step (in ratio)
  for (double m : {2.0, 5.0, 10.0})
    if (std::abs(std::log(m * mag / raw)) < std::abs(std::log(step / raw))) step = m * mag;
  const double eps = step * 1e-9;
  for (double t = std::ceil((lo - eps) / step) * step; t <= hi + eps; t += step)
    ticks.push_back(std::abs(t) < eps ? 0.0 : t);
  return ticks;
}

std::vector<double> LogTicks(double lo, double hi) {
  std::vector<double> ticks;
  if (!(lo > 0) || !(hi > lo) || !std::isfinite(hi)) return ticks;
  const int k0 = int(std::floor(std::log10(lo))), k1 = int(std::ceil(std::log10(hi)));
  const bool fine = std::log10(hi) - std::log10(lo) < 2.5;  // few decades: add 2 and 5 x 10^k
  for (int k = k0; k <= k1; ++k)
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !fine) continue;
      const double t = m * std::pow(10.0, k);
      if (t >= lo * (1 - 1e-9) && t <= hi * (1 + 1e-9)) ticks.push_back(t);
    }
  return ticks;
}

std::string FormatTick(double value, double step) {
  char buf[48];
  const double a = std::abs(value);
  if (a != 0.0 && (a >= 1e6 || a < 1e-4)) {
    std::snprintf(buf, sizeof(buf), "%.3g", value);
  } else {
    int decimals = step > 0 ? std::max(0, int(std::ceil(-std::log10(step) - 1e-9))) : 2;
    // A step like 0.25 needs one decimal more than its magnitude says.
    if (step > 0 && std::abs(std::round(step * std::pow(10.0, decimals)) - step * std::pow(10.0, decimals)) > 1e-6)
      ++decimals;
    std::snprintf(buf, sizeof(buf), "%.*f", std::min(decimals, 6), value);
  }
  return buf;
}

std::string Px(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.2f", v);
  return buf;
}

void Range::Add(double v, bool log) {
  if (!std::isfinite(v) || (log && v <= 0)) return;
  if (!valid) lo = hi = v, valid = true;
  lo = std::min(lo, v);
  hi = std::max(hi, v);
}

void FinalizeRange(Range* r, double fixed_min, double fixed_max, bool include_zero, bool log, bool margin) {
  if (include_zero && !log) r->Add(0.0, false);
  if (!r->valid) *r = Range{log ? 0.1 : 0.0, 1.0, true};
  if (log) {
    double a = std::log10(r->lo), b = std::log10(r->hi);
    if (b - a < 1e-12) a -= 0.5, b += 0.5;
    const double m = margin ? 0.04 * (b - a) : 0.0;
    r->lo = std::pow(10.0, a - m), r->hi = std::pow(10.0, b + m);
  } else {
    if (r->hi - r->lo < 1e-12 * std::max(1.0, std::abs(r->hi))) r->lo -= 1.0, r->hi += 1.0;
    const double m = margin ? 0.04 * (r->hi - r->lo) : 0.0;
    // Keep an exact zero boundary (bars, counts) instead of pushing it negative.
    const bool zero_lo = include_zero && r->lo == 0.0;
    r->lo -= zero_lo ? 0.0 : m;
    r->hi += m;
  }
  if (std::isfinite(fixed_min) && (!log || fixed_min > 0)) r->lo = fixed_min;
  if (std::isfinite(fixed_max) && (!log || fixed_max > 0)) r->hi = fixed_max;
  if (r->hi <= r->lo) r->hi = r->lo + (log ? r->lo : 1.0);
}

Canvas::Canvas(const PlotOptions& options, double right_extra_px) : options_(options) {
  left_ = kMarginLeft;
  top_ = (options.title.empty() ? 12.0 : kMarginTop) + (options.legend_above && options.legend ? 18.0 : 0.0);
  width_ = std::max(40.0, options.width_px - kMarginLeft - kMarginRight - right_extra_px);
  height_ = std::max(40.0, options.height_px - top_ - kMarginBottom);
}

void Canvas::SetRanges(Range x, Range y) {
  x_ = x, y_ = y;
  if (!options_.equal_aspect || options_.log_x || options_.log_y) return;
  const double sx = width_ / (x_.hi - x_.lo), sy = height_ / (y_.hi - y_.lo);
  const double s = std::min(sx, sy);
  const double cx = 0.5 * (x_.lo + x_.hi), cy = 0.5 * (y_.lo + y_.hi);
  x_.lo = cx - 0.5 * width_ / s, x_.hi = cx + 0.5 * width_ / s;
  y_.lo = cy - 0.5 * height_ / s, y_.hi = cy + 0.5 * height_ / s;
}

double Canvas::X(double v) const {
  const double u = options_.log_x ? (std::log10(v) - std::log10(x_.lo)) / (std::log10(x_.hi) - std::log10(x_.lo))
                                  : (v - x_.lo) / (x_.hi - x_.lo);
  return left_ + u * width_;
}

double Canvas::Y(double v) const {
  const double u = options_.log_y ? (std::log10(v) - std::log10(y_.lo)) / (std::log10(y_.hi) - std::log10(y_.lo))
                                  : (v - y_.lo) / (y_.hi - y_.lo);
  return top_ + height_ - u * height_;
}

bool Canvas::InX(double v) const { return std::isfinite(v) && (!options_.log_x || v > 0); }
bool Canvas::InY(double v) const { return std::isfinite(v) && (!options_.log_y || v > 0); }

void Canvas::DrawFrame(const std::vector<std::string>& x_categories) {
  std::ostringstream& o = body_;
  o << "<rect x=\"0\" y=\"0\" width=\"" << options_.width_px << "\" height=\"" << options_.height_px
    << "\" fill=\"white\"/>\n";
  DrawXTicks(x_categories);
  DrawYTicks();
  o << "<rect class=\"plot-area\" x=\"" << Px(left_) << "\" y=\"" << Px(top_) << "\" width=\"" << Px(width_)
    << "\" height=\"" << Px(height_) << "\" fill=\"none\" stroke=\"#333\"/>\n";
  if (!options_.x_label.empty())
    o << "<text class=\"x-label\" x=\"" << Px(left_ + width_ / 2) << "\" y=\"" << Px(options_.height_px - 8.0)
      << "\" text-anchor=\"middle\">" << XmlEscape(options_.x_label) << "</text>\n";
  if (!options_.y_label.empty())
    o << "<text class=\"y-label\" x=\"14\" y=\"" << Px(top_ + height_ / 2) << "\" text-anchor=\"middle\" "
      << "transform=\"rotate(-90 14 " << Px(top_ + height_ / 2) << ")\">" << XmlEscape(options_.y_label)
      << "</text>\n";
  if (!options_.title.empty())
    o << "<text class=\"title\" x=\"" << Px(left_ + width_ / 2) << "\" y=\"19\" text-anchor=\"middle\" "
      << "font-size=\"13\" font-weight=\"bold\">" << XmlEscape(options_.title) << "</text>\n";
}

void Canvas::DrawXTicks(const std::vector<std::string>& x_categories) {
  std::ostringstream& o = body_;
  const double bottom = top_ + height_;
  // numbers, or one category name at each integer
  std::vector<std::pair<double, std::string>> xt;
  if (!x_categories.empty()) {
    for (size_t i = 0; i < x_categories.size(); ++i) xt.push_back({double(i), x_categories[i]});
  } else {
    const std::vector<double> t = options_.log_x ? LogTicks(x_.lo, x_.hi)
                                                 : NiceTicks(x_.lo, x_.hi, std::max(3, int(width_ / 75)));
    for (double v : t) xt.push_back({v, FormatTick(v, options_.log_x ? v : (t.size() > 1 ? t[1] - t[0] : 1.0))});
  }
  size_t longest = 0;
  for (const auto& [v, s] : xt) longest = std::max(longest, s.size());
  const bool slant = !x_categories.empty() && longest * 7.0 > width_ / std::max<size_t>(1, xt.size());
  o << "<g class=\"x-ticks\" font-size=\"11\" fill=\"#333\">\n";
  for (const auto& [v, s] : xt) {
    const double px = X(v);
    if (options_.grid && x_categories.empty())
      o << "<line x1=\"" << Px(px) << "\" y1=\"" << Px(top_) << "\" x2=\"" << Px(px) << "\" y2=\"" << Px(bottom)
        << "\" stroke=\"#e6e6e6\"/>\n";
    o << "<line x1=\"" << Px(px) << "\" y1=\"" << Px(bottom) << "\" x2=\"" << Px(px) << "\" y2=\""
      << Px(bottom + 4) << "\" stroke=\"#333\"/>\n";
    if (slant)
      o << "<text x=\"" << Px(px) << "\" y=\"" << Px(bottom + 14) << "\" text-anchor=\"end\" transform=\"rotate(-30 "
        << Px(px) << " " << Px(bottom + 14) << ")\">" << XmlEscape(s) << "</text>\n";
    else
      o << "<text x=\"" << Px(px) << "\" y=\"" << Px(bottom + 16) << "\" text-anchor=\"middle\">" << XmlEscape(s)
        << "</text>\n";
  }
  o << "</g>\n";
}

void Canvas::DrawYTicks() {
  std::ostringstream& o = body_;
  const std::vector<double> yt = options_.log_y ? LogTicks(y_.lo, y_.hi)
                                                : NiceTicks(y_.lo, y_.hi, std::max(3, int(height_ / 45)));
  o << "<g class=\"y-ticks\" font-size=\"11\" fill=\"#333\">\n";
  for (double v : yt) {
    const double py = Y(v);
    if (options_.grid)
      o << "<line x1=\"" << Px(left_) << "\" y1=\"" << Px(py) << "\" x2=\"" << Px(left_ + width_) << "\" y2=\""
        << Px(py) << "\" stroke=\"#e6e6e6\"/>\n";
    o << "<line x1=\"" << Px(left_ - 4) << "\" y1=\"" << Px(py) << "\" x2=\"" << Px(left_) << "\" y2=\"" << Px(py)
      << "\" stroke=\"#333\"/>\n";
    o << "<text x=\"" << Px(left_ - 7) << "\" y=\"" << Px(py + 4) << "\" text-anchor=\"end\">"
      << XmlEscape(FormatTick(v, options_.log_y ? v : (yt.size() > 1 ? yt[1] - yt[0] : 1.0))) << "</text>\n";
  }
  o << "</g>\n";
}

void Canvas::DrawRefLines() {
  // Labels alternate (vertical lines: first row / second row; horizontal: left / right end) so that two
  // nearby lines (RMSE and median) keep readable labels.
  std::ostringstream& o = body_;
  for (const XSpan& span : options_.xspans) {
    if (options_.log_x || !(span.x1 >= x_.lo && span.x0 <= x_.hi)) continue;
    const double p0 = X(std::max(span.x0, x_.lo)), p1 = X(std::min(span.x1, x_.hi));
    o << "<rect class=\"span\" x=\"" << Px(std::min(p0, p1)) << "\" y=\"" << Px(top_) << "\" width=\""
      << Px(std::max(std::fabs(p1 - p0), 1.5)) << "\" height=\"" << Px(height_) << "\" fill=\"" << span.color
      << "\" fill-opacity=\"0.15\"/>\n";
  }
  int k = 0;
  for (const RefLine& l : options_.vlines) {
    if (!InX(l.value) || l.value < x_.lo || l.value > x_.hi) continue;
    const double px = X(l.value), ty = top_ + 12 + 12 * (k % 2);
    const bool right = px > left_ + 0.8 * width_;  // label left of the line near the right edge
    o << "<line class=\"ref\" x1=\"" << Px(px) << "\" y1=\"" << Px(top_) << "\" x2=\"" << Px(px) << "\" y2=\""
      << Px(top_ + height_) << "\" stroke=\"" << l.color << "\" stroke-dasharray=\"4,3\"/>\n";
    o << "<text x=\"" << Px(right ? px - 3 : px + 3) << "\" y=\"" << Px(ty) << "\" font-size=\"10\" fill=\""
      << l.color << "\"" << (right ? " text-anchor=\"end\"" : "") << ">" << XmlEscape(l.label) << "</text>\n";
    ++k;
  }
  k = 0;
  for (const RefLine& l : options_.hlines) {
    if (!InY(l.value) || l.value < y_.lo || l.value > y_.hi) continue;
    const double py = Y(l.value), ty = py - 3 < top_ + 12 ? py + 12 : py - 3;
    const bool right = k % 2 == 1;
    o << "<line class=\"ref\" x1=\"" << Px(left_) << "\" y1=\"" << Px(py) << "\" x2=\"" << Px(left_ + width_)
      << "\" y2=\"" << Px(py) << "\" stroke=\"" << l.color << "\" stroke-dasharray=\"4,3\"/>\n";
    o << "<text x=\"" << Px(right ? left_ + width_ - 4 : left_ + 4) << "\" y=\"" << Px(ty)
      << "\" font-size=\"10\" fill=\"" << l.color << "\"" << (right ? " text-anchor=\"end\"" : "") << ">"
      << XmlEscape(l.label) << "</text>\n";
    ++k;
  }
}

void Canvas::DrawLegend(const std::vector<LegendEntry>& all) {
  std::vector<LegendEntry> entries;
  for (const LegendEntry& e : all)
    if (!e.label.empty()) entries.push_back(e);
  if (!options_.legend || entries.empty()) return;
  size_t chars = 0;
  for (const LegendEntry& e : entries) chars = std::max(chars, e.label.size());
  const double w = 36.0 + 6.3 * double(chars), h = 8.0 + 16.0 * double(entries.size());
  double x0 = left_ + width_ - w - 6;
  const double y0 = top_ + 6;
  std::ostringstream& o = body_;
  o << "<g class=\"legend\" font-size=\"11\">\n";
  if (!options_.legend_above)
    o << "<rect x=\"" << Px(x0) << "\" y=\"" << Px(y0) << "\" width=\"" << Px(w) << "\" height=\"" << Px(h)
      << "\" fill=\"white\" fill-opacity=\"0.85\" stroke=\"#bbb\"/>\n";
  double row_x = left_;  // legend_above: entries side by side just above the plot area
  for (size_t i = 0; i < entries.size(); ++i) {
    const LegendEntry& e = entries[i];
    double cy = y0 + 12 + 16.0 * double(i);
    if (options_.legend_above) {
      x0 = row_x - 6, cy = top_ - 10;
      row_x += 40.0 + 6.3 * double(e.label.size());
    }
    if (e.box)
      o << "<rect x=\"" << Px(x0 + 8) << "\" y=\"" << Px(cy - 5) << "\" width=\"16\" height=\"10\" fill=\"" << e.color
        << "\"/>\n";
    if (e.line)
      o << "<line x1=\"" << Px(x0 + 6) << "\" y1=\"" << Px(cy) << "\" x2=\"" << Px(x0 + 26) << "\" y2=\"" << Px(cy)
        << "\" stroke=\"" << e.color << "\" stroke-width=\"2\"" << DashAttr(e.dashed) << "/>\n";
    if (e.marker)
      o << "<circle cx=\"" << Px(x0 + 16) << "\" cy=\"" << Px(cy) << "\" r=\"3\" fill=\"" << e.color << "\"/>\n";
    o << "<text x=\"" << Px(x0 + 30) << "\" y=\"" << Px(cy + 4) << "\">" << XmlEscape(e.label) << "</text>\n";
  }
  o << "</g>\n";
}

void Canvas::DrawSeries(const PlotSeries& s, const std::string& color) {
  std::ostringstream& o = body_;
  const size_t n = std::min(s.x.size(), s.y.size());
  o << "<g class=\"series\" clip-path=\"url(#@CLIP@)\">\n";
  if (s.y_err.size() >= n)
    for (size_t i = 0; i < n; ++i) {
      if (!InX(s.x[i]) || !std::isfinite(s.y_err[i]) || !InY(s.y[i] - s.y_err[i]) || !InY(s.y[i] + s.y_err[i]))
        continue;
      const double px = X(s.x[i]), y0 = Y(s.y[i] - s.y_err[i]), y1 = Y(s.y[i] + s.y_err[i]);
      o << "<path d=\"M" << Px(px) << " " << Px(y0) << "V" << Px(y1) << "M" << Px(px - 3) << " " << Px(y0) << "h6M"
        << Px(px - 3) << " " << Px(y1) << "h6\" stroke=\"" << color << "\" fill=\"none\"/>\n";
    }
  if (s.line) {
    std::string points;
    auto flush = [&] {
      if (!points.empty())
        o << "<polyline fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << Px(s.line_width_px)
          << "\" stroke-linejoin=\"round\"" << DashAttr(s.dashed) << " points=\"" << points << "\"/>\n";
      points.clear();
    };
    for (size_t i = 0; i < n; ++i) {
      if (!InX(s.x[i]) || !InY(s.y[i])) {
        flush();
        continue;
      }
      points += (points.empty() ? "" : " ") + Px(X(s.x[i])) + "," + Px(Y(s.y[i]));
    }
    flush();
  }
  if (s.markers)
    for (size_t i = 0; i < n; ++i)
      if (InX(s.x[i]) && InY(s.y[i]))
        o << "<circle cx=\"" << Px(X(s.x[i])) << "\" cy=\"" << Px(Y(s.y[i])) << "\" r=\"" << Px(s.marker_radius_px)
          << "\" fill=\"" << color << "\"/>\n";
  o << "</g>\n";
}

void Canvas::NoData() {
  body_ << "<text class=\"no-data\" x=\"" << Px(left_ + width_ / 2) << "\" y=\"" << Px(top_ + height_ / 2)
        << "\" text-anchor=\"middle\" fill=\"#888\">no data</text>\n";
}

std::string Canvas::Finish() const {
  std::string body = body_.str();
  const std::string id = HashId(body);
  for (size_t pos = body.find("@CLIP@"); pos != std::string::npos; pos = body.find("@CLIP@", pos))
    body.replace(pos, 6, id);
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" width=\""
    << options_.width_px << "\" height=\"" << options_.height_px << "\" viewBox=\"0 0 " << options_.width_px << " "
    << options_.height_px << "\" font-family=\"DejaVu Sans, Arial, sans-serif\" font-size=\"" << kFontPx
    << "\" data-x-min=\"" << x_.lo << "\" data-x-max=\"" << x_.hi << "\" data-y-min=\"" << y_.lo
    << "\" data-y-max=\"" << y_.hi << "\">\n";
  o << "<defs><clipPath id=\"" << id << "\"><rect x=\"" << Px(left_) << "\" y=\"" << Px(top_) << "\" width=\""
    << Px(width_) << "\" height=\"" << Px(height_) << "\"/></clipPath></defs>\n";
  o << body << "</svg>\n";
  return o.str();
}

}  // namespace rotolidar::bench::svg
