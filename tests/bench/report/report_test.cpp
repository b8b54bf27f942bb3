// The report writers: SVG plots are well-formed with the expected elements and axis ranges, the raster's PNG
// carries the right colours, and the HTML report of a small synthetic run has every section (with truth) or
// leaves the truth sections out with a note (without).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "bench/metrics/coverage.hpp"
#include "bench/report/html_report.hpp"
#include "bench/report/run_report.hpp"
#include "bench/report/svg_plot.hpp"
#include "bench/report/svg_raster.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/io/trajectory_io.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

/// Balanced, properly nested tags (self-closing "/>" and <!...> / <?...?> allowed); the root count is returned.
bool WellFormed(const std::string& xml, std::string* why, int* roots = nullptr) {
  std::vector<std::string> stack;
  int n_roots = 0;
  for (size_t i = xml.find('<'); i != std::string::npos; i = xml.find('<', i + 1)) {
    const size_t end = xml.find('>', i);
    if (end == std::string::npos) return *why = "unterminated tag at " + std::to_string(i), false;
    const std::string tag = xml.substr(i + 1, end - i - 1);
    if (tag.empty()) return *why = "empty tag", false;
    if (tag[0] == '!' || tag[0] == '?') continue;
    if (tag[0] == '/') {
      if (stack.empty() || stack.back() != tag.substr(1)) return *why = "unbalanced </" + tag.substr(1) + ">", false;
      stack.pop_back();
      continue;
    }
    const std::string name = tag.substr(0, tag.find_first_of(" \n\t/"));
    if (stack.empty()) ++n_roots;
    if (tag.back() != '/') stack.push_back(name);
  }
  if (roots) *roots = n_roots;
  if (!stack.empty()) return *why = "unclosed <" + stack.back() + ">", false;
  return true;
}

size_t Count(const std::string& s, const std::string& what) {
  size_t n = 0;
  for (size_t i = s.find(what); i != std::string::npos; i = s.find(what, i + 1)) ++n;
  return n;
}

/// Elements `what` inside every <g ...`group_attr`...> group (groups hold no nested groups).
size_t CountInGroups(const std::string& svg, const std::string& group_attr, const std::string& what) {
  size_t n = 0;
  for (size_t i = svg.find(group_attr); i != std::string::npos; i = svg.find(group_attr, i + 1))
    n += Count(svg.substr(i, svg.find("</g>", i) - i), what);
  return n;
}

double RootAttr(const std::string& svg, const std::string& name) {
  std::smatch m;
  EXPECT_TRUE(std::regex_search(svg, m, std::regex(name + "=\"([-0-9.e+]+)\""))) << name;
  return m.empty() ? NAN : std::stod(m[1]);
}

PlotSeries Series(const std::string& label, std::vector<double> x, std::vector<double> y, bool markers = false) {
  PlotSeries s;
  s.label = label;
  s.x = std::move(x);
  s.y = std::move(y);
  s.markers = markers;
  return s;
}

TEST(SvgPlot, LinePlotIsWellFormedWithTicksLegendAndRange) {
  PlotSeries a = Series("sin", {}, {}), b = Series("a < b & c", {}, {}, true);
  for (int i = 0; i <= 100; ++i) {
    a.x.push_back(0.1 * i), a.y.push_back(std::sin(0.1 * i));
    b.x.push_back(0.1 * i), b.y.push_back(0.5 * std::cos(0.1 * i));
  }
  PlotOptions o;
  o.title = "test";
  o.x_label = "time [s]";
  o.y_label = "value [m]";
  o.hlines = {{0.25, "ref", "#f00"}};
  const std::string svg = LinePlotSvg({a, b}, o);
  std::string why;
  int roots = 0;
  ASSERT_TRUE(WellFormed(svg, &why, &roots)) << why;
  EXPECT_EQ(roots, 1);
  EXPECT_EQ(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\"", 0), 0u);
  EXPECT_EQ(Count(svg, "<polyline"), 2u);
  EXPECT_EQ(Count(svg, "<circle"), 101u + 1u);  // b's markers + its legend marker
  EXPECT_NE(svg.find(">a &lt; b &amp; c<"), std::string::npos);
  EXPECT_NE(svg.find(">time [s]<"), std::string::npos);
  EXPECT_NE(svg.find(">value [m]<"), std::string::npos);
  // x data [0, 10] with the 4 % margin; ticks at nice values include both ends.
  EXPECT_NEAR(RootAttr(svg, "data-x-min"), -0.4, 1e-9);
  EXPECT_NEAR(RootAttr(svg, "data-x-max"), 10.4, 1e-9);
  EXPECT_LT(RootAttr(svg, "data-y-min"), -0.99);
  EXPECT_GT(RootAttr(svg, "data-y-max"), 0.99);
  EXPECT_NE(svg.find(">0<"), std::string::npos);
  EXPECT_NE(svg.find(">10<"), std::string::npos);
  EXPECT_NE(svg.find(">ref<"), std::string::npos);
}

TEST(SvgPlot, EqualAspectGivesOneScaleOnBothAxes) {
  const PlotSeries s = Series("path", {0, 10, 10, 0, 0}, {0, 0, 2, 2, 0});
  PlotOptions o;
  o.equal_aspect = true;
  o.width_px = 500;
  o.height_px = 500;
  const std::string svg = LinePlotSvg({s}, o);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, std::regex("class=\"plot-area\" x=\"[-0-9.]+\" y=\"[-0-9.]+\" width=\"([0-9.]+)\" "
                                                   "height=\"([0-9.]+)\"")));
  const double w_px = std::stod(m[1]), h_px = std::stod(m[2]);
  const double dx = RootAttr(svg, "data-x-max") - RootAttr(svg, "data-x-min");
  const double dy = RootAttr(svg, "data-y-max") - RootAttr(svg, "data-y-min");
  EXPECT_NEAR(w_px / dx, h_px / dy, 1e-3 * w_px / dx);  // pixels per metre equal (attributes carry 2 decimals)
  EXPECT_GE(dx, 10.0);
  EXPECT_GE(dy, 2.0);
}

TEST(SvgPlot, LogAxisScatterHistogramAndBars) {
  PlotOptions o;
  o.log_y = true;
  const std::string log = ScatterPlotSvg({Series("p", {1, 2, 3}, {0.01, 1.0, 100.0})}, o);
  std::string why;
  ASSERT_TRUE(WellFormed(log, &why)) << why;
  EXPECT_EQ(Count(log, "<circle"), 3u + 1u);
  EXPECT_EQ(Count(log, "<polyline"), 0u);
  for (const char* t : {">0.01<", ">1<", ">100<"}) EXPECT_NE(log.find(t), std::string::npos) << t;

  HistogramOptions h;
  h.bins = 4;
  h.min = 0.0;
  h.max = 4.0;
  const std::string hist = HistogramSvg({0.5, 1.5, 1.6, 3.5, 9.0}, h, PlotOptions{});
  ASSERT_TRUE(WellFormed(hist, &why)) << why;
  EXPECT_EQ(CountInGroups(hist, "class=\"bars\"", "<rect"), 3u);  // bin [2, 3) is empty
  EXPECT_NE(hist.find("1 values outside the range"), std::string::npos);
  EXPECT_NEAR(RootAttr(hist, "data-y-min"), 0.0, 1e-12);

  const std::string bar = BarChartSvg({"lab", "corridor"}, {{"A", {1.0, 2.0}, {0.1, 0.2}, ""}, {"B", {1.5, NAN}, {}, ""}},
                                      PlotOptions{});
  ASSERT_TRUE(WellFormed(bar, &why)) << why;
  EXPECT_NE(bar.find(">lab<"), std::string::npos);
  EXPECT_NE(bar.find(">corridor<"), std::string::npos);
  EXPECT_EQ(CountInGroups(bar, "class=\"bars\"", "<rect"), 3u);  // B has no bar for corridor
  EXPECT_EQ(CountInGroups(bar, "class=\"bars\"", "<path"), 2u);  // A's error bars
  EXPECT_EQ(CountInGroups(bar, "class=\"legend\"", "<text"), 2u);
  EXPECT_GE(RootAttr(bar, "data-y-max"), 2.2);

  const std::string empty = LinePlotSvg({}, PlotOptions{});
  ASSERT_TRUE(WellFormed(empty, &why)) << why;
  EXPECT_NE(empty.find("no data"), std::string::npos);
}

TEST(SvgRaster, Base64MatchesRfc4648) {
  auto b64 = [](const std::string& s) { return Base64Encode(std::vector<uint8_t>(s.begin(), s.end())); };
  EXPECT_EQ(b64(""), "");
  EXPECT_EQ(b64("M"), "TQ==");
  EXPECT_EQ(b64("Ma"), "TWE=");
  EXPECT_EQ(b64("Man"), "TWFu");
  EXPECT_EQ(b64("foobar"), "Zm9vYmFy");
}

std::vector<uint8_t> Base64Decode(const std::string& s) {
  const std::string abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<uint8_t> out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    if (c == '=') break;
    acc = (acc << 6) | uint32_t(abc.find(c));
    if ((bits += 6) >= 8) out.push_back(uint8_t((acc >> (bits -= 8)) & 0xff));
  }
  return out;
}

TEST(SvgRaster, TopViewColoursCellsByValue) {
  // Left half (x < 0) value 0, right half value 1, over a 4 m x 2 m area; fixed scale [0, 1].
  std::vector<Eigen::Vector2d> xy;
  std::vector<double> v;
  for (double x = -2.0; x <= 2.0; x += 0.01)
    for (double y = -1.0; y <= 1.0; y += 0.01) xy.emplace_back(x, y), v.push_back(x < 0 ? 0.0 : 1.0);
  TopViewOptions t;
  t.value_min = 0.0;
  t.value_max = 1.0;
  t.colorbar_label = "value [-]";
  PlotOptions o;
  o.x_label = "x [m]";
  const std::string svg = PointTopViewSvg(xy, v, t, o);
  std::string why;
  ASSERT_TRUE(WellFormed(svg, &why)) << why;
  EXPECT_NE(svg.find(">value [-]<"), std::string::npos);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, std::regex("data:image/png;base64,([A-Za-z0-9+/=]+)\"")));
  const std::vector<uint8_t> png = Base64Decode(m[1]);
  const cv::Mat img = cv::imdecode(png, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(img.type(), CV_8UC4);
  // The raster tiles the (equal-aspect) plot area: sample a quarter and three quarters along the middle row.
  const double x_lo = RootAttr(svg, "data-x-min"), x_hi = RootAttr(svg, "data-x-max");
  auto pixel = [&](double x_m) {
    return img.at<cv::Vec4b>(img.rows / 2, int((x_m - x_lo) / (x_hi - x_lo) * img.cols));
  };
  uint8_t r, g, b;
  ColormapRgb(Colormap::kViridis, 0.0, &r, &g, &b);
  EXPECT_EQ(pixel(-1.0), cv::Vec4b(b, g, r, 255));
  ColormapRgb(Colormap::kViridis, 1.0, &r, &g, &b);
  EXPECT_EQ(pixel(1.0), cv::Vec4b(b, g, r, 255));
  EXPECT_EQ(img.at<cv::Vec4b>(0, 0)[3], 0);  // outside the data: transparent (the plot frame shows through)
}

/// A small synthetic run in the box room: the truth loops inside the room, the estimate is the truth in the
/// SLAM world (base at the first pose) with a deterministic few-millimetre wobble, and the map is the room's
/// surface samples moved into the SLAM world — so every report section has real data behind it.
struct SyntheticRun {
  std::string dir, recording, slam_dir;
  SlamRunResult slam;
};

SyntheticRun MakeRun(const std::string& name, bool with_truth) {
  SyntheticRun run;
  run.dir = (fs::temp_directory_path() / ("rotolidar_report_test_" + name)).string();
  fs::remove_all(run.dir);
  run.recording = run.dir + "/recording", run.slam_dir = run.dir + "/slam";
  fs::create_directories(run.recording + "/truth");
  fs::create_directories(run.slam_dir);
  Trajectory truth;
  for (int i = 0; i <= 200; ++i) {  // 10 s at 20 Hz, a 2 m radius circle at 1.2 m height
    const double t = 0.05 * i, a = 0.6 * t;
    truth.push_back({t, MakePose({0.5 + 2.0 * std::cos(a), 2.0 * std::sin(a), 1.2},
                                 Eigen::Quaterniond(Eigen::AngleAxisd(a + M_PI / 2, Eigen::Vector3d::UnitZ())))});
  }
  const Pose3 T_slam_scene = truth.front().T_ref_body.inverse();
  for (int i = 0; i < 100; ++i) {
    const StampedPose& p = truth[size_t(2 * i)];
    Pose3 T = T_slam_scene * p.T_ref_body;
    T.translation() += 0.004 * Eigen::Vector3d(std::sin(1.3 * i), std::cos(0.7 * i), 0.0);
    run.slam.trajectory.push_back({p.t_s, T});
    ScanReport r;
    r.t_start_s = p.t_s, r.t_end_s = p.t_s + 0.1;
    r.registration.attempted = r.registration.converged = i > 0;
    if (i >= 40 && i < 43) r.registration.converged = false, r.registration.message = "test failure";  // one stretch
    r.timings = {2.0, 3.0, 4.0, 10.0 + i % 7, 1.0, 2.0, 22.0 + i % 7};
    run.slam.scans.push_back(r);
  }
  run.slam.data_duration_s = 10.0, run.slam.wall_time_s = 2.5, run.slam.median_scan_ms = 25.0;
  sim::Scene scene;
  EXPECT_TRUE(sim::LoadScene(sim::ResolveScenePath("box_room"), &scene).ok);
  std::vector<Eigen::Vector3d> map;
  for (const SurfaceSample& s : SampleSurfaces(sim::BuildMesh(scene), 0.05, Eigen::AlignedBox3d()))
    map.push_back(T_slam_scene * s.p_world.cast<double>());
  run.slam.map_points = map.size();
  EXPECT_TRUE(SavePointCloud(run.slam_dir + "/map.ply", map).ok);
  if (with_truth) {
    EXPECT_TRUE(WriteTrajectory(run.recording + "/truth/base.tum", TrajectoryFormat::kTum, truth).ok);
  }
  std::ofstream(run.recording + "/sim_config.yaml") << "scene: box_room\n";
  std::ofstream(run.slam_dir + "/slam_config.yaml") << "# synthetic\n";
  return run;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(RunReport, SyntheticRunWithTruthHasEverySection) {
  const SyntheticRun run = MakeRun("truth", true);
  RunEvaluation ev;
  const Status s = WriteSlamRunReport(run.recording, run.slam_dir, run.slam, RunEvaluationOptions{}, &ev);  // --score
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_TRUE(ev.has_truth) << ev.truth_note;
  ASSERT_TRUE(ev.has_map_metrics) << ev.map_note;
  // The wobble 4 mm * (sin, cos) has an RMS of exactly 4 mm; the alignment absorbs almost none of it
  // (measured RMSE 0.00400 m). A wrong association or alignment gives centimetres to metres.
  EXPECT_NEAR(ev.ape.stats.rmse, 0.004, 0.0004);
  EXPECT_GT(ev.rpe.stats.count, 50u);  // ~12 m walked, all pairs 1 m apart: one per start pose
  // The map is the scene's own surface samples moved back by the APE alignment: distances are the alignment
  // error (measured median 5e-8 m, max 1.8e-4 m) and the 0.05 m sample grid covers itself (measured 1.0). A map
  // left in the SLAM frame, or moved by the wrong transform, is off by metres.
  EXPECT_LT(ev.map.map_to_truth.max_m, 0.002);
  EXPECT_GT(ev.map.coverage.total.coverage, 0.99);
  const std::string html = ReadAll(run.slam_dir + "/report.html");
  std::string why;
  ASSERT_TRUE(WellFormed(html, &why)) << why;
  for (const char* id : {"headline", "trajectory", "ape", "rpe", "health", "timing", "map", "coverage", "elements",
                         "config"})
    EXPECT_NE(html.find(std::string("<section id=\"") + id + "\">"), std::string::npos) << id;
  // The 3 failed scans: one row in the health table, shaded in the APE and timing plots.
  EXPECT_NE(html.find("<td>registration failed</td>"), std::string::npos);
  EXPECT_NE(html.find("3 of 100 scans did not converge"), std::string::npos);
  size_t spans = 0;
  for (size_t at = html.find("class=\"span\""); at != std::string::npos; at = html.find("class=\"span\"", at + 1))
    ++spans;
  EXPECT_EQ(spans, 2u);
  EXPECT_NE(html.find(Fmt("%.4f m", ev.ape.stats.rmse)), std::string::npos);
  EXPECT_NE(html.find("main_door"), std::string::npos);
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  EXPECT_EQ(html.find("Left out"), std::string::npos);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);  // self-contained
  const nlohmann::json j = nlohmann::json::parse(ReadAll(run.slam_dir + "/metrics.json"));
  for (const char* key : {"slam", "ape_translation_m", "rpe_translation_m", "map"}) EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_NEAR(j["ape_translation_m"]["rmse"].get<double>(), ev.ape.stats.rmse, 1e-12);
  EXPECT_NEAR(j["slam"]["stage_mean_ms"]["deskew"].get<double>(), 2.0, 1e-12);
}

// `rotolidar slam` without --score: the trajectory is scored against truth (cheap), the map is not (minutes).
TEST(RunReport, WithoutScoreTheMapIsNotScored) {
  const SyntheticRun run = MakeRun("no_score", true);
  RunEvaluationOptions options;
  options.map_metrics = false;
  RunEvaluation ev;
  const Status s = WriteSlamRunReport(run.recording, run.slam_dir, run.slam, options, &ev);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_TRUE(ev.has_truth) << ev.truth_note;
  EXPECT_NEAR(ev.ape.stats.rmse, 0.004, 0.0004);
  EXPECT_FALSE(ev.has_map_metrics);
  EXPECT_NE(ev.map_note.find("--score"), std::string::npos) << ev.map_note;
  const nlohmann::json j = nlohmann::json::parse(ReadAll(run.slam_dir + "/metrics.json"));
  EXPECT_TRUE(j.contains("ape_translation_m"));
  EXPECT_FALSE(j.contains("map"));
  const std::string html = ReadAll(run.slam_dir + "/report.html");
  std::string why;
  ASSERT_TRUE(WellFormed(html, &why)) << why;
  for (const char* id : {"coverage", "elements"})
    EXPECT_EQ(html.find(std::string("<section id=\"") + id + "\">"), std::string::npos) << id;
  EXPECT_NE(html.find("--score"), std::string::npos);
}

// A walker's returns in truth/dynamic_hits.csv: three map points next to those in free space count, the floor
// points next to its foot do not (static surface); the share reaches metrics.json and the report's map section.
TEST(RunReport, DynamicShareReachesMetricsJsonAndTheReport) {
  const SyntheticRun run = MakeRun("dynamic", true);
  // MakeRun's SLAM world is the base at the first truth pose: (2.5, 0, 1.2), yawed by 90 deg.
  const Pose3 T_slam_scene =
      MakePose({2.5, 0.0, 1.2}, Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()))).inverse();
  const Eigen::Vector3d c(-1.0, -1.5, 1.2);  // free space in the box room
  std::vector<Eigen::Vector3d> map;
  ASSERT_TRUE(LoadPointCloud(run.slam_dir + "/map.ply", &map).ok);
  for (const Eigen::Vector3d& d : {Eigen::Vector3d(0.02, 0.01, 0.0), Eigen::Vector3d(0.0, 0.03, 0.02),
                                   Eigen::Vector3d(0.04, -0.02, 0.01)})
    map.push_back(T_slam_scene * (c + d));
  ASSERT_TRUE(SavePointCloud(run.slam_dir + "/map.ply", map).ok);
  {
    std::ofstream hits(run.recording + "/truth/dynamic_hits.csv");
    hits << "t_s,object_id,x_m,y_m,z_m\n";
    for (int i = 0; i < 4; ++i) hits << 1.0 + i << ",0," << c.x() + 0.01 * i << "," << c.y() << "," << c.z() << "\n";
    hits << "5,0,-1.0,-1.5,0.04\n5.1,0,-1.02,-1.5,0.06\n";  // its foot, just above the floor
  }
  RunEvaluationOptions options;
  options.map_metrics = false;  // the dynamic share does not need them
  RunEvaluation ev;
  const Status s = WriteSlamRunReport(run.recording, run.slam_dir, run.slam, options, &ev);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_TRUE(ev.has_dynamic) << ev.dynamic_note;
  EXPECT_EQ(ev.dynamic.returns_seen, 6u);
  EXPECT_EQ(ev.dynamic.map_points_dynamic, 3u);
  const nlohmann::json j = nlohmann::json::parse(ReadAll(run.slam_dir + "/metrics.json"));
  ASSERT_TRUE(j.contains("dynamic"));
  EXPECT_EQ(j["dynamic"]["map_points_dynamic"].get<size_t>(), 3u);
  EXPECT_EQ(j["dynamic"]["static_clearance_m"].get<double>(), 0.15);
  EXPECT_NE(ReadAll(run.slam_dir + "/report.html").find("dynamic objects: 6 returns seen"), std::string::npos);

  fs::remove(run.recording + "/truth/dynamic_hits.csv");  // a recording from before the file: a note, no share
  ASSERT_TRUE(WriteSlamRunReport(run.recording, run.slam_dir, run.slam, options, &ev).ok);
  EXPECT_FALSE(ev.has_dynamic);
  EXPECT_NE(ev.dynamic_note.find("dynamic_hits.csv"), std::string::npos) << ev.dynamic_note;
  EXPECT_FALSE(nlohmann::json::parse(ReadAll(run.slam_dir + "/metrics.json")).contains("dynamic"));
}

TEST(RunReport, RunWithoutTruthLeavesTruthSectionsOut) {
  const SyntheticRun run = MakeRun("no_truth", false);
  RunEvaluation ev;
  const Status s = WriteSlamRunReport(run.recording, run.slam_dir, run.slam, RunEvaluationOptions{}, &ev);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_FALSE(ev.has_truth);
  EXPECT_FALSE(ev.has_map_metrics);
  EXPECT_EQ(ev.map_points.size(), run.slam.map_points);  // the map is still shown, in the SLAM world
  const std::string html = ReadAll(run.slam_dir + "/report.html");
  std::string why;
  ASSERT_TRUE(WellFormed(html, &why)) << why;
  for (const char* id : {"headline", "trajectory", "timing", "map", "config"})
    EXPECT_NE(html.find(std::string("<section id=\"") + id + "\">"), std::string::npos) << id;
  for (const char* id : {"ape", "rpe", "coverage", "elements"})
    EXPECT_EQ(html.find(std::string("<section id=\"") + id + "\">"), std::string::npos) << id;
  EXPECT_NE(html.find("no ground truth"), std::string::npos);
  EXPECT_NE(html.find("height z [m]"), std::string::npos);
  EXPECT_EQ(html.find("ATE RMSE"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(ReadAll(run.slam_dir + "/metrics.json"));
  EXPECT_TRUE(j.contains("slam"));
  EXPECT_FALSE(j.contains("ape_translation_m"));
  EXPECT_FALSE(j.contains("map"));
}

}  // namespace
}  // namespace rotolidar::bench
