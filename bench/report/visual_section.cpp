#include "bench/report/visual_section.hpp"

#include <algorithm>
#include <functional>
#include <map>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bench/report/svg_plot.hpp"
#include "bench/report/svg_raster.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"
#include "core/visual/feature_tracker.hpp"

namespace rotolidar::bench::report {
namespace {

/// One line per label over the scans that fused a frame, against time since the first scan; `values` gives a
/// scan's values in label order.
std::string CameraSeriesSvg(const std::vector<ScanReport>& scans, const std::vector<std::string>& labels,
                            const std::function<std::vector<double>(const VisualScanReport&)>& values,
                            const std::string& title, const std::string& y_label) {
  std::vector<PlotSeries> series(labels.size());
  for (size_t k = 0; k < labels.size(); ++k) series[k].label = labels[k];
  const Seconds t0 = scans.front().t_start_s;
  for (const ScanReport& r : scans) {
    if (!r.visual.image) continue;
    const std::vector<double> v = values(r.visual);
    for (size_t k = 0; k < series.size(); ++k) series[k].x.push_back(r.t_start_s - t0), series[k].y.push_back(v[k]);
  }
  PlotOptions options;
  options.title = title;
  options.x_label = "time [s]";
  options.y_label = y_label;
  options.y_include_zero = true;
  options.legend_above = true;
  return LinePlotSvg(series, options);
}

/// Observations, inliers, LiDAR depths and landmarks per scan over time.
std::string StatisticsSvg(const std::vector<ScanReport>& scans) {
  return CameraSeriesSvg(
      scans, {"observations", "KLT inliers", "new LiDAR depths", "landmarks in the window"},
      [](const VisualScanReport& v) {
        return std::vector<double>{double(v.observations), double(v.inliers), double(v.lidar_depths),
                                   double(v.landmarks)};
      },
      "Camera path per scan", "count");
}

/// The camera's weight over time: the pixel sigma the window whitens with (adaptive) and the median
/// reprojection error of each solve; with td estimated, td in ms too.
std::string WeightSvg(const std::vector<ScanReport>& scans) {
  const bool td = std::any_of(scans.begin(), scans.end(), [](const ScanReport& r) {
    return r.visual.image && r.visual.time_offset_s != 0.0;
  });
  std::vector<std::string> labels = {"sigma [px]", "median reprojection error [px]"};
  if (td) labels.push_back("time offset td [ms]");
  return CameraSeriesSvg(
      scans, labels,
      [td](const VisualScanReport& v) {
        std::vector<double> out = {v.sigma_px, v.residual_median_px};
        if (td) out.push_back(1e3 * v.time_offset_s);
        return out;
      },
      "Camera weight per scan", td ? "px (ms)" : "px");
}

/// The frame at t_s with the features tracked over the half second before it: each track's last positions as a
/// line, its current position as a dot (red: new, orange: 2-9 frames, green: 10 or more). Empty on failure.
std::string TrackedFrameSvg(const std::vector<CameraFrameRef>& frames, Seconds t_s, const RigCalib& calib) {
  visual::FeatureTracker tracker;
  std::map<uint64_t, std::vector<cv::Point2f>> history;
  visual::FeatureTrackResult last;
  CameraFrame frame;
  for (const CameraFrameRef& ref : frames) {
    if (ref.t_s < t_s - 0.5 || ref.t_s > t_s) continue;
    if (!LoadCameraFrame(ref, &frame)) return "";
    last = tracker.Track(frame, calib.camera);
    if (!last.ok) return "";
    for (const visual::TrackedFeature& f : last.features)
      history[f.id].push_back(cv::Point2f(float(f.pixel_px.x()), float(f.pixel_px.y())));
  }
  if (!last.ok || frame.image.empty()) return "";
  cv::Mat canvas = frame.image.clone();
  for (const visual::TrackedFeature& f : last.features) {
    const std::vector<cv::Point2f>& h = history[f.id];
    for (size_t k = h.size() > 10 ? h.size() - 10 : 1; k < h.size(); ++k)
      cv::line(canvas, h[k - 1], h[k], cv::Scalar(0, 255, 255), 1, cv::LINE_AA);
    const cv::Scalar color = f.track_length >= 10 ? cv::Scalar(0, 200, 0)
                             : f.track_length >= 2 ? cv::Scalar(0, 165, 255) : cv::Scalar(0, 0, 255);
    cv::circle(canvas, h.back(), 3, color, cv::FILLED, cv::LINE_AA);
  }
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", canvas, png)) return "";
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" width=\"" +
         std::to_string(canvas.cols) + "\" height=\"" + std::to_string(canvas.rows) + "\"><image width=\"" +
         std::to_string(canvas.cols) + "\" height=\"" + std::to_string(canvas.rows) +
         "\" xlink:href=\"data:image/png;base64," + Base64Encode(png) + "\"/></svg>";
}

}  // namespace

void AddVisualSection(const RunReportInput& in, HtmlReport* html) {
  const std::vector<ScanReport>& scans = in.slam->scans;
  const size_t used =
      size_t(std::count_if(scans.begin(), scans.end(), [](const ScanReport& r) { return r.visual.image; }));
  if (used == 0) return;
  html->BeginSection("camera", "Camera in the window");
  html->Paragraph(std::to_string(used) + " of " + std::to_string(scans.size()) +
                  " scans fused a camera frame (docs/visual.md; per scan: scans.csv vis_* columns).");
  html->Figure(StatisticsSvg(scans), "Per scan: features observed, KLT inliers of the frame used, new landmarks "
                                     "that took a LiDAR depth, and landmarks held by the window.");
  html->Figure(WeightSvg(scans), "The camera's weight: the pixel sigma of the next solve (raised from the nominal "
                                 "when the residuals say the camera is poor) and each solve's median reprojection "
                                 "error (docs/visual.md, \"A poor camera\").");
  std::vector<CameraFrameRef> frames;
  RigCalib calib;
  if (in.recording_dir.empty() || !LoadCameraIndex(in.recording_dir, &frames) || frames.empty() ||
      !LoadCalibYaml(in.recording_dir + "/calib.yaml", &calib)) {
    html->Note("no sample frames: the recording's camera frames or calib.yaml could not be read");
    return;
  }
  const Seconds t0 = scans.front().t_start_s, t1 = scans.back().t_start_s;
  for (double share : {0.25, 0.5, 0.75}) {
    const Seconds t = t0 + share * (t1 - t0);
    const std::string svg = TrackedFrameSvg(frames, t, calib);
    if (svg.empty()) continue;
    html->Figure(svg, Fmt("Frame at %.1f s, tracked over the half second before it (default tracker settings): "
                          "dots red = new, orange = 2-9 frames, green = 10+; yellow = the last positions.",
                          t - t0));
  }
}

}  // namespace rotolidar::bench::report
