// `rotolidar bench plane-residuals`: range noise on flat surfaces of a real capture and/or the twin
// (bench/eval/plane_residuals.hpp), with a real-vs-twin table and histograms when both are given.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include "bench/cli/options.hpp"
#include "bench/cli/perf_commands.hpp"
#include "bench/eval/plane_residuals.hpp"
#include "bench/eval/twin_capture.hpp"
#include "bench/report/svg_plot.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rotolidar::bench {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

Status ParseXyz(const std::string& text, Eigen::Vector3d* v) {
  std::istringstream in(text);
  char c1 = 0, c2 = 0;
  double x = 0, y = 0, z = 0;
  if (!(in >> x >> c1 >> y >> c2 >> z) || c1 != ',' || c2 != ',') {
    return Status::Error("expected x,y,z, got '" + text + "'");
  }
  *v = Eigen::Vector3d(x, y, z);
  return Status::Ok();
}

/// |residual| histograms of the real capture and the twin, side by side, as one SVG.
std::string SideBySideHistograms(const PlaneResidualResult& real, const PlaneResidualResult& twin, double max_m) {
  auto histogram = [&](const PlaneResidualResult& r, const std::string& title, size_t color) {
    std::vector<double> mm;
    for (const PlaneResidual& p : r.points) mm.push_back(1e3 * std::abs(p.residual_m));
    HistogramOptions h;
    h.bins = 40, h.min = 0.0, h.max = 1e3 * max_m, h.color = PaletteColor(color);
    PlotOptions o;
    o.title = title;
    o.x_label = "|residual to fitted plane| [mm]";
    o.width_px = 560, o.height_px = 380;
    return HistogramSvg(mm, h, o);
  };
  std::string left = histogram(real, "real VLP-16 (median " + std::to_string(std::lround(1e3 * real.all.median_abs_m)) +
                                         " mm)", 0);
  std::string right = histogram(twin, "twin (median " + std::to_string(std::lround(1e3 * twin.all.median_abs_m)) +
                                          " mm)", 1);
  right.insert(4, " x=\"560\"");  // after "<svg"
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"1120\" height=\"380\">" + left + right + "</svg>\n";
}

/// The same two histograms as a PNG (OpenCV drawing; for docs, where SVG with embedded text is not rendered):
/// fraction of points per 2.5 mm bin of |residual|, real left, twin right, equal axes.
Status SideBySidePng(const PlaneResidualResult& real, const PlaneResidualResult& twin, double max_m,
                     const std::string& path) {
  constexpr int kBins = 40, kW = 560, kH = 380, kLeft = 60, kBottom = 50, kTop = 40;
  auto fractions = [&](const PlaneResidualResult& r) {
    std::vector<double> f(kBins, 0.0);
    for (const PlaneResidual& p : r.points) {
      const int b = static_cast<int>(std::abs(p.residual_m) / max_m * kBins);
      if (b >= 0 && b < kBins) f[static_cast<std::size_t>(b)] += 1.0 / static_cast<double>(r.points.size());
    }
    return f;
  };
  const std::vector<double> fr = fractions(real), ft = fractions(twin);
  const double top = std::max(*std::max_element(fr.begin(), fr.end()), *std::max_element(ft.begin(), ft.end()));
  cv::Mat img(kH, 2 * kW, CV_8UC3, cv::Scalar(255, 255, 255));
  auto panel = [&](const std::vector<double>& f, int x0, const std::string& title, const cv::Scalar& color,
                   const ResidualBin& all) {
    const int plot_w = kW - kLeft - 20, plot_h = kH - kBottom - kTop;
    for (int b = 0; b < kBins; ++b) {
      const int x = x0 + kLeft + b * plot_w / kBins, x2 = x0 + kLeft + (b + 1) * plot_w / kBins - 1;
      const int h = static_cast<int>(f[static_cast<std::size_t>(b)] / top * plot_h);
      cv::rectangle(img, {x, kTop + plot_h - h}, {x2, kTop + plot_h}, color, cv::FILLED);
    }
    cv::rectangle(img, {x0 + kLeft, kTop}, {x0 + kLeft + plot_w, kTop + plot_h}, cv::Scalar(0, 0, 0), 1);
    for (int t = 0; t <= 4; ++t) {  // x ticks every max/4
      const int x = x0 + kLeft + t * plot_w / 4;
      cv::putText(img, std::to_string(static_cast<int>(std::lround(1e3 * max_m * t / 4))), {x - 10, kTop + plot_h + 18},
                  cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
    cv::putText(img, "|residual to fitted plane| [mm]", {x0 + kLeft + 100, kH - 10}, cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    char text[160];
    std::snprintf(text, sizeof(text), "%s: median %.1f mm, p90 %.1f mm", title.c_str(), 1e3 * all.median_abs_m,
                  1e3 * all.p90_abs_m);
    cv::putText(img, text, {x0 + kLeft, 25}, cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, "fraction", {x0 + 5, kTop + 12}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
  };
  panel(fr, 0, "real VLP-16", cv::Scalar(180, 119, 31), real.all);  // BGR of tab10 blue / orange
  panel(ft, kW, "twin", cv::Scalar(14, 127, 255), twin.all);
  if (!cv::imwrite(path, img)) return Status::Error(path + ": cannot write PNG");
  return Status::Ok();
}

void PrintComparisonTable(const char* what, const std::vector<ResidualBin>& real,
                          const std::vector<ResidualBin>& twin, std::ostream& os) {
  os << what << "  real: n  median  p90 | twin: n  median  p90 [mm] | twin/real median  p90\n";
  char line[200];
  for (std::size_t i = 0; i < real.size() && i < twin.size(); ++i) {
    const ResidualBin& a = real[i];
    const ResidualBin& b = twin[i];
    if (a.count == 0 && b.count == 0) continue;
    std::snprintf(line, sizeof(line), "%5.1f - %-5.1f %9zu %7.1f %5.1f | %7zu %7.1f %5.1f | %8.2f %6.2f\n", a.lo, a.hi,
                  a.count, 1e3 * a.median_abs_m, 1e3 * a.p90_abs_m, b.count, 1e3 * b.median_abs_m,
                  1e3 * b.p90_abs_m, a.count ? b.median_abs_m / a.median_abs_m : 0.0,
                  a.count ? b.p90_abs_m / a.p90_abs_m : 0.0);
    os << line;
  }
}

void PrintComparison(const PlaneResidualResult& real, const PlaneResidualResult& twin, std::ostream& os) {
  PrintComparisonTable("range [m]    ", real.by_range, twin.by_range, os);
  PrintComparisonTable("incidence [deg]", real.by_incidence, twin.by_incidence, os);
  PrintComparisonTable("all          ", {real.all}, {twin.all}, os);
}

}  // namespace

int BenchPlaneResiduals(int argc, char** argv) {
  OptionParser p("bench plane-residuals",
                 "Residuals of VLP-16 points to RANSAC planes (PCL), binned by range and incidence: of a capture "
                 "(raw 1206-byte payloads *.bin, pcap, or recording folder; the head must not move), of the twin "
                 "(--twin-scene) or of both, compared.");
  p.AddPositional("input", "capture to measure (empty: the twin only)", "-");
  p.Add("csv", "", "-", "write the per-point residuals of the capture (or of the twin alone) to this CSV");
  p.Add("twin-csv", "", "-", "write the twin's per-point residuals to this CSV");
  p.Add("figure", "", "-", "with a capture and a twin: side-by-side |residual| histograms (SVG) to this file");
  p.Add("figure-png", "", "-", "the same histograms as a PNG");
  p.Add("threshold", "0.10", "m", "RANSAC inlier band = residual window");
  p.Add("max-planes", "8", "-", "planes per revolution");
  p.Add("min-plane-points", "400", "-", "smallest plane used");
  p.Add("min-range", "1", "m", "points closer are not used");
  p.Add("max-range", "60", "m", "points farther are not used");
  p.Add("twin-scene", "", "-", "simulate the twin in this scene (name or path)");
  p.Add("twin-at", "0,0,1", "m", "twin lidar position x,y,z in the scene");
  p.Add("twin-rpy-deg", "0,0,0", "deg", "twin lidar roll,pitch,yaw");
  p.Add("revolutions", "13", "-", "twin revolutions");
  p.Add("seed", "1", "-", "twin run seed");
  p.Add("s0", "0.03", "m", "twin range_noise_sigma_m");
  p.Add("s1", "0", "m/m", "twin range_noise_per_m");
  p.Add("k", "0", "-", "twin range_noise_incidence_exponent");
  p.Add("cmin", "0.1", "-", "twin range_noise_min_cos");
  p.Add("weak-power", "0", "-", "twin range_noise_weak_power");
  p.Add("beam-rings", "0", "-", "twin beam_rings");
  p.Add("weak-gain", "3", "-", "twin range_noise_weak_max_gain");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  PlaneResidualOptions o;
  TwinCaptureOptions t;
  long planes = 0, min_points = 0, revs = 0, seed = 0, rings = 0;
  for (const Status& s : {p.GetDouble("threshold", &o.ransac_threshold_m), p.GetInt("max-planes", &planes),
                          p.GetInt("min-plane-points", &min_points), p.GetDouble("min-range", &o.min_range_m),
                          p.GetDouble("max-range", &o.max_range_m), p.GetInt("revolutions", &revs),
                          p.GetInt("seed", &seed), p.GetDouble("s0", &t.lidar.range_noise_sigma_m),
                          p.GetDouble("s1", &t.lidar.range_noise_per_m),
                          p.GetDouble("k", &t.lidar.range_noise_incidence_exponent),
                          p.GetDouble("cmin", &t.lidar.range_noise_min_cos),
                          p.GetDouble("weak-power", &t.lidar.range_noise_weak_power),
                          p.GetDouble("weak-gain", &t.lidar.range_noise_weak_max_gain),
                          p.GetInt("beam-rings", &rings)}) {
    if (!s) return std::cerr << "error: " << s.message << "\n", 2;
  }
  o.max_planes = static_cast<int>(planes), o.min_plane_points = static_cast<int>(min_points);
  t.revolutions = static_cast<int>(revs), t.seed = static_cast<uint64_t>(seed), t.lidar.beam_rings = static_cast<int>(rings);
  Eigen::Vector3d at, rpy;
  for (const Status& s : {ParseXyz(p.Get("twin-at"), &at), ParseXyz(p.Get("twin-rpy-deg"), &rpy)}) {
    if (!s) return std::cerr << "error: bench plane-residuals: " << s.message << "\n", 2;
  }
  t.T_world_lidar.linear() = (Eigen::AngleAxisd(rpy.z() * kDegToRad, Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(rpy.y() * kDegToRad, Eigen::Vector3d::UnitY()) *
                              Eigen::AngleAxisd(rpy.x() * kDegToRad, Eigen::Vector3d::UnitX()))
                                 .toRotationMatrix();
  t.T_world_lidar.translation() = at;
  t.scene = p.Get("twin-scene");
  const std::string input = p.Get("input") == "-" ? "" : p.Get("input");
  if (input.empty() && t.scene.empty()) return std::cerr << "error: give an input and/or --twin-scene\n", 2;
  PlaneResidualResult real, twin;
  auto fail = [](const Status& s) { return std::cerr << "error: " << s.message << "\n", 1; };
  if (!input.empty()) {
    std::vector<LidarScan> scans;
    if (Status s = LoadLidarRevolutions(input, &scans); !s) return fail(s);
    if (Status s = MeasurePlaneResiduals(scans, o, &real); !s) return fail(s);
    std::cout << "capture " << input << "\n";
    PrintPlaneResiduals(real, std::cout);
    if (!p.Get("csv").empty()) {
      if (Status s = WritePlaneResidualCsv(p.Get("csv"), real); !s) return fail(s);
    }
  }
  if (!t.scene.empty()) {
    std::vector<LidarScan> scans;
    if (Status s = CaptureTwinRevolutions(t, &scans); !s) return fail(s);
    if (Status s = MeasurePlaneResiduals(scans, o, &twin); !s) return fail(s);
    std::cout << "twin in " << t.scene << "\n";
    PrintPlaneResiduals(twin, std::cout);
    const std::string csv = input.empty() ? p.Get("csv") : p.Get("twin-csv");
    if (!csv.empty()) {
      if (Status s = WritePlaneResidualCsv(csv, twin); !s) return fail(s);
    }
  }
  if (!input.empty() && !t.scene.empty()) {
    PrintComparison(real, twin, std::cout);
    if (!p.Get("figure").empty()) {
      std::ofstream svg(p.Get("figure"));
      svg << SideBySideHistograms(real, twin, o.ransac_threshold_m);
      if (!svg) return fail(Status::Error(p.Get("figure") + ": cannot write"));
    }
    if (!p.Get("figure-png").empty()) {
      if (Status s = SideBySidePng(real, twin, o.ransac_threshold_m, p.Get("figure-png")); !s) return fail(s);
    }
  }
  return 0;
}

}  // namespace rotolidar::bench
