// The visual front end on synthetic images: a randomly textured plane rendered at known camera poses (the true
// motion of every pixel is a homography), so each tracked feature can be checked against its true position.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <optional>
#include <set>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/types/geometry.hpp"
#include "core/visual/feature_tracker.hpp"

namespace rotolidar::visual {
namespace {

constexpr int kMargin = 240;  // the texture canvas extends this far [px] beyond the first view on every side

CameraIntrinsics Pinhole() { return CameraIntrinsics(); }  // 640x480, f = 462 px, no distortion

Eigen::Matrix3d K(const CameraIntrinsics& c) {
  Eigen::Matrix3d k;
  k << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1;
  return k;
}

// A random grey texture (fixed seed): a smooth background of random 40 px cells under random rectangles and discs,
// blurred (sigma 1.2 px) so that the bilinear resampling of the views stays close to the true warp (the errors the
// tests measure include it).
cv::Mat MakeTexture(uint64_t seed, cv::Size size, double contrast = 1.0) {
  cv::RNG rng(seed);
  cv::Mat cells(size.height / 40 + 2, size.width / 40 + 2, CV_8UC1);
  rng.fill(cells, cv::RNG::UNIFORM, 60, 196);
  cv::Mat tex;
  cv::resize(cells, tex, cv::Size(cells.cols * 40, cells.rows * 40), 0, 0, cv::INTER_CUBIC);
  tex = tex(cv::Rect(0, 0, size.width, size.height)).clone();
  const int shapes = size.area() / 400;
  for (int i = 0; i < shapes; ++i) {
    const cv::Point p(rng.uniform(0, size.width), rng.uniform(0, size.height));
    const cv::Scalar grey(rng.uniform(0, 256));
    if (i % 2) cv::rectangle(tex, p, p + cv::Point(rng.uniform(4, 30), rng.uniform(4, 30)), grey, cv::FILLED);
    else cv::circle(tex, p, rng.uniform(3, 16), grey, cv::FILLED);
  }
  cv::GaussianBlur(tex, tex, cv::Size(0, 0), 1.2);
  if (contrast != 1.0) tex.convertTo(tex, CV_8U, contrast, 128.0 * (1.0 - contrast));
  return tex;
}

cv::Mat MakeCanvas(uint64_t seed = 7) { return MakeTexture(seed, cv::Size(640 + 2 * kMargin, 480 + 2 * kMargin)); }

// Homography from view-1 pixels to view-k pixels for the plane n^T X1 = d (view-1 camera frame) and the camera
// motion T_k_1 (X_k = R X_1 + t): H = K (R + t n^T / d) K^-1.
Eigen::Matrix3d PlaneHomography(const Pose3& T_k_1, const Eigen::Vector3d& n, double d, const CameraIntrinsics& c) {
  return K(c) * (T_k_1.linear() + T_k_1.translation() * n.transpose() / d) * K(c).inverse();
}

Eigen::Vector2d Apply(const Eigen::Matrix3d& H, const Eigen::Vector2d& p) {
  return (H * p.homogeneous()).hnormalized();
}

// True when p lies at least `margin` px inside a 640x480 image (11: a whole 21 px KLT window).
bool Inside(const Eigen::Vector2d& p, double margin = 11.0) {
  return p.x() >= margin && p.y() >= margin && p.x() <= 639 - margin && p.y() <= 479 - margin;
}

// View k of the canvas, BGR8: view-1 pixel u shows canvas pixel u + margin; view k is view 1 moved by H_k_1.
// With distortion, every measured pixel is undistorted to find the ideal pixel it sees.
cv::Mat Render(const cv::Mat& canvas, const Eigen::Matrix3d& H_k_1, const CameraIntrinsics& c) {
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();
  shift(0, 2) = shift(1, 2) = -kMargin;
  const Eigen::Matrix3d view_from_canvas = H_k_1 * shift;
  cv::Mat grey;
  if (c.k1 == 0.0 && c.k2 == 0.0 && c.p1 == 0.0 && c.p2 == 0.0) {
    cv::Matx33d H;
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col) H(r, col) = view_from_canvas(r, col);
    cv::warpPerspective(canvas, grey, H, cv::Size(c.width_px, c.height_px), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  } else {
    std::vector<cv::Point2d> pixels, norm;
    for (int v = 0; v < c.height_px; ++v)
      for (int u = 0; u < c.width_px; ++u) pixels.emplace_back(u, v);
    const cv::Mat Kcv = (cv::Mat_<double>(3, 3) << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1);
    cv::undistortPoints(pixels, norm, Kcv, std::vector<double>{c.k1, c.k2, c.p1, c.p2}, cv::noArray(), cv::noArray(),
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-9));
    cv::Mat map_x(c.height_px, c.width_px, CV_32FC1), map_y(c.height_px, c.width_px, CV_32FC1);
    const Eigen::Matrix3d canvas_from_ideal = view_from_canvas.inverse() * K(c);
    for (size_t i = 0; i < norm.size(); ++i) {
      const Eigen::Vector2d q = Apply(canvas_from_ideal, Eigen::Vector2d(norm[i].x, norm[i].y));
      map_x.at<float>(int(i) / c.width_px, int(i) % c.width_px) = float(q.x());
      map_y.at<float>(int(i) / c.width_px, int(i) % c.width_px) = float(q.y());
    }
    cv::remap(canvas, grey, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  }
  cv::Mat bgr;
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

CameraFrame Frame(double t_s, cv::Mat image) { return CameraFrame{t_s, std::move(image)}; }

// A general motion in front of a tilted plane 3 m away: ~6 px of translation and ~5 px of rotation flow per frame.
const Eigen::Vector3d kPlaneNormal = Eigen::Vector3d(0.15, -0.1, 1.0).normalized();
constexpr double kPlaneDistanceM = 3.0;
Pose3 SequencePose(int k) {
  Pose3 T = Pose3::Identity();
  T.linear() = ExpSO3(k * Eigen::Vector3d(0.004, -0.01, 0.003));
  T.translation() = k * Eigen::Vector3d(0.04, -0.015, 0.05);
  return T;
}
Eigen::Matrix3d SequenceHomography(int k) {
  return PlaneHomography(SequencePose(k), kPlaneNormal, kPlaneDistanceM, Pinhole());
}
CameraFrame SequenceFrame(const cv::Mat& canvas, int k) {
  return Frame(0.1 * k, Render(canvas, SequenceHomography(k), Pinhole()));
}

std::map<uint64_t, TrackedFeature> ById(const FeatureTrackResult& r) {
  std::map<uint64_t, TrackedFeature> m;
  for (const TrackedFeature& f : r.features) m[f.id] = f;
  return m;
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(FeatureTracker, TracksMatchTheTrueHomography) {
  const cv::Mat canvas = MakeCanvas();
  FeatureTracker tracker;
  const FeatureTrackResult r1 = tracker.Track(SequenceFrame(canvas, 0), Pinhole());
  ASSERT_TRUE(r1.ok) << r1.message;
  EXPECT_EQ(r1.stats.new_features, 150);
  std::map<uint64_t, std::pair<int, Eigen::Vector2d>> first;  // id -> (frame, pixel) of its first observation
  for (const TrackedFeature& f : r1.features) first[f.id] = {0, f.pixel_px};
  std::vector<double> errors;
  double track_ms = 0.0;
  for (int k = 1; k <= 4; ++k) {
    const FeatureTrackResult r = tracker.Track(SequenceFrame(canvas, k), Pinhole());
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_TRUE(r.stats.ransac_ran);
    EXPECT_GE(r.stats.inliers, 0.9 * r.stats.previous) << "frame " << k;
    track_ms += r.stats.time_ms;
    for (const TrackedFeature& f : r.features) {
      if (!first.count(f.id)) {
        first[f.id] = {k, f.pixel_px};
        continue;
      }
      const auto& [j, p] = first[f.id];
      const Eigen::Vector2d truth = Apply(SequenceHomography(k) * SequenceHomography(j).inverse(), p);
      errors.push_back((f.pixel_px - truth).norm());
    }
  }
  const double max_error = *std::max_element(errors.begin(), errors.end());
  std::printf("[ tracker ] %zu tracked positions over 4 frames: median error %.3f px, max %.3f px; first frame "
              "%.2f ms, tracking frames %.2f ms mean (640x480)\n",
              errors.size(), Median(errors), max_error, r1.stats.time_ms, track_ms / 4);
  // KLT on a blurred, bilinearly resampled texture: sub-0.1 px per frame, drifting as a random walk over 4 frames.
  EXPECT_LT(Median(errors), 0.3);
  EXPECT_LT(max_error, 1.0);
}

// A pure yaw of 10 deg moves the image by ~81 px, about what the coarsest level of a 4-level pyramid can still
// reach: plain KLT loses or mistracks most features, the gyro-hinted tracker starts next to the answer.
TEST(FeatureTracker, RotationHintKeepsTracksUnderLargeRotation) {
  const cv::Mat canvas = MakeCanvas();
  Pose3 T_2_1 = Pose3::Identity();
  T_2_1.linear() = Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d H = PlaneHomography(T_2_1, kPlaneNormal, kPlaneDistanceM, Pinhole());  // = K R K^-1
  const cv::Mat image1 = Render(canvas, Eigen::Matrix3d::Identity(), Pinhole());
  const cv::Mat image2 = Render(canvas, H, Pinhole());
  const Eigen::Matrix3d R_prev_cur = T_2_1.linear().transpose();  // R_1_2: current (2) into previous (1)
  int correct[2] = {0, 0}, visible = 0, crowded = 0;
  for (int hinted = 0; hinted < 2; ++hinted) {
    FeatureTracker tracker;
    const FeatureTrackResult r1 = tracker.Track(Frame(0.0, image1), Pinhole());
    const FeatureTrackResult r2 = tracker.Track(Frame(0.033, image2), Pinhole(),
                                                hinted ? std::optional<Eigen::Matrix3d>(R_prev_cur) : std::nullopt);
    ASSERT_TRUE(r1.ok && r2.ok) << r2.message;
    const auto seen = ById(r2);
    visible = crowded = 0;
    for (const TrackedFeature& f : r1.features) {
      const Eigen::Vector2d truth = Apply(H, f.pixel_px);
      if (!Inside(truth)) continue;
      ++visible;
      // The rotation stretches the image by up to 20 % in x near the right edge (1/cos^2 of the ray angle), which
      // KLT's translation-only window follows with up to ~1.2 px of bias: 1.5 px tells right from wrong.
      auto it = seen.find(f.id);
      if (it != seen.end() && (it->second.pixel_px - truth).norm() < 1.5) ++correct[hinted];
      // It also compresses the left half by up to 9 %: features detected 30-33 px apart come closer than
      // min_distance_px, and the younger (higher id) one is dropped by design. Those are not tracking failures.
      if (it == seen.end() && std::any_of(r2.features.begin(), r2.features.end(), [&](const TrackedFeature& g) {
            return g.id < f.id && (g.pixel_px - truth).norm() < 30.0;
          }))
        ++crowded;
    }
    std::printf("[ tracker ] 10 deg yaw, %s: %d of %d visible features tracked correctly, %d dropped as crowded "
                "(stats: tracked %d, fb-rejected %d, ransac-rejected %d, crowded %d)\n",
                hinted ? "with hint" : "no hint", correct[hinted], visible, crowded, r2.stats.tracked,
                r2.stats.rejected_fb, r2.stats.rejected_ransac, r2.stats.rejected_crowded);
  }
  EXPECT_LT(correct[0], 0.5 * visible);
  EXPECT_GE(correct[1], 0.9 * (visible - crowded));
}

// Two planes seen from view 1: a near one (2 m, facing the camera) over view-1 columns u < kSplitU, and a far one
// (5 m, tilted) behind everything, so that the scene is not planar (a single plane leaves the essential matrix
// two-fold ambiguous, and RANSAC may pick the wrong E). View k shows the near plane where its region has moved to.
struct TwoPlaneScene {
  static constexpr double kSplitU = 300.0;
  cv::Mat near_canvas = MakeCanvas(11), far_canvas = MakeCanvas(12);
  static Eigen::Matrix3d Near(const Pose3& T_k_1) {
    return PlaneHomography(T_k_1, Eigen::Vector3d::UnitZ(), 2.0, Pinhole());
  }
  static Eigen::Matrix3d Far(const Pose3& T_k_1) { return PlaneHomography(T_k_1, kPlaneNormal, 5.0, Pinhole()); }
  cv::Mat View(const Pose3& T_k_1) const {
    cv::Mat image = Render(far_canvas, Far(T_k_1), Pinhole()), mask = cv::Mat::zeros(image.size(), CV_8UC1);
    std::vector<cv::Point> region;
    const double l = -kMargin, r = kSplitU, t = -kMargin, b = 480 + kMargin;
    for (const Eigen::Vector2d& c : {Eigen::Vector2d(l, t), Eigen::Vector2d(r, t), Eigen::Vector2d(r, b),
                                     Eigen::Vector2d(l, b)}) {
      const Eigen::Vector2d q = Apply(Near(T_k_1), c);
      region.emplace_back(cvRound(q.x()), cvRound(q.y()));
    }
    cv::fillConvexPoly(mask, region, cv::Scalar(255));
    Render(near_canvas, Near(T_k_1), Pinhole()).copyTo(image, mask);
    return image;
  }
  // Where the view-1 pixel p is seen in view k; nullopt within 15 px of the depth edge (mixed windows, occlusion).
  static std::optional<Eigen::Vector2d> Truth(const Pose3& T_k_1, const Eigen::Vector2d& p) {
    if (std::abs(p.x() - kSplitU) < 15.0) return std::nullopt;
    const Eigen::Vector2d q = Apply(p.x() < kSplitU ? Near(T_k_1) : Far(T_k_1), p);
    const Eigen::Vector2d edge = Apply(Near(T_k_1), Eigen::Vector2d(kSplitU, p.y()));
    if (p.x() > kSplitU && q.x() < edge.x() + 15.0) return std::nullopt;  // occluded by the near plane
    return q;
  }
};

// A 180x180 object with its own texture pasted into `image` at `at`.
cv::Mat WithObject(cv::Mat image, const cv::Point& at) {
  cv::Mat object_bgr;
  cv::cvtColor(MakeTexture(99, cv::Size(180, 180)), object_bgr, cv::COLOR_GRAY2BGR);
  object_bgr.copyTo(image(cv::Rect(at, object_bgr.size())));
  return image;
}

// An independently moving object (its own texture, 12 px down between the frames) in front of the two planes while
// the camera moves sideways: its features break the epipolar constraint by ~12 px and RANSAC must drop them.
TEST(FeatureTracker, RansacRejectsAnIndependentlyMovingObject) {
  const TwoPlaneScene scene;
  const cv::Rect box1(430, 140, 180, 180);
  Pose3 T_2_1 = Pose3::Identity();
  T_2_1.linear() = ExpSO3(Eigen::Vector3d(0.0, 0.005, 0.002));
  T_2_1.translation() = Eigen::Vector3d(-0.08, 0.01, 0.02);  // 18 px of parallax on the near plane, 7 on the far
  FeatureTracker tracker;
  const FeatureTrackResult r1 =
      tracker.Track(Frame(0.0, WithObject(scene.View(Pose3::Identity()), box1.tl())), Pinhole());
  const FeatureTrackResult r2 =
      tracker.Track(Frame(0.1, WithObject(scene.View(T_2_1), box1.tl() + cv::Point(3, 12))), Pinhole());
  ASSERT_TRUE(r1.ok && r2.ok) << r2.message;
  const auto seen = ById(r2);
  int on_object = 0, object_kept = 0, static_features = 0, static_kept = 0;
  double static_max_error = 0.0;
  const cv::Rect inner(box1.x + 11, box1.y + 11, box1.width - 22, box1.height - 22);  // whole KLT window inside
  const cv::Rect outer(box1.x - 11, box1.y - 11, box1.width + 22 + 3, box1.height + 22 + 12);
  for (const TrackedFeature& f : r1.features) {
    const cv::Point p(int(f.pixel_px.x()), int(f.pixel_px.y()));
    const auto it = seen.find(f.id);
    if (inner.contains(p)) {
      ++on_object;
      object_kept += it != seen.end();
      continue;
    }
    const std::optional<Eigen::Vector2d> truth = TwoPlaneScene::Truth(T_2_1, f.pixel_px);
    if (outer.contains(p) || !truth || !Inside(*truth)) continue;
    ++static_features;
    if (it == seen.end()) continue;
    ++static_kept;
    static_max_error = std::max(static_max_error, (it->second.pixel_px - *truth).norm());
  }
  std::printf("[ tracker ] moving object: %d of %d object features kept, %d of %d static kept (max error %.3f px); "
              "stats: tracked %d, fb %d, ransac %d\n", object_kept, on_object, static_kept, static_features,
              static_max_error, r2.stats.tracked, r2.stats.rejected_fb, r2.stats.rejected_ransac);
  ASSERT_GE(on_object, 8);
  EXPECT_TRUE(r2.stats.ransac_ran);
  EXPECT_EQ(object_kept, 0);
  EXPECT_GE(r2.stats.rejected_ransac, on_object);
  EXPECT_GE(static_kept, 0.95 * static_features);
  EXPECT_LT(static_max_error, 0.5);
}

void ExpectSpread(const FeatureTrackResult& r, double min_distance_px) {
  for (size_t i = 0; i < r.features.size(); ++i)
    for (size_t j = i + 1; j < r.features.size(); ++j)
      EXPECT_GE((r.features[i].pixel_px - r.features[j].pixel_px).norm(), min_distance_px)
          << r.features[i].id << " " << r.features[j].id;
}

std::vector<int> GridCounts(const FeatureTrackResult& r, int rows, int cols) {
  std::vector<int> counts(rows * cols, 0);
  for (const TrackedFeature& f : r.features)
    ++counts[int(f.pixel_px.y() * rows / 480) * cols + int(f.pixel_px.x() * cols / 640)];
  return counts;
}

TEST(FeatureTracker, FeaturesCoverTheImageAndKeepTheirDistance) {
  const cv::Mat canvas = MakeCanvas();
  FeatureTracker tracker;
  const FeatureTrackResult r1 = tracker.Track(SequenceFrame(canvas, 0), Pinhole());
  ASSERT_TRUE(r1.ok);
  EXPECT_EQ(r1.stats.total, 150);
  const std::vector<int> counts = GridCounts(r1, 4, 4);
  EXPECT_GE(*std::min_element(counts.begin(), counts.end()), 1);
  ExpectSpread(r1, 30.0);
  // Zooming out (the camera backs off by 10 % of the depth per frame) pulls the tracks together: crowded ones are
  // dropped, shorter first. Every track dropped for crowding must have a kept neighbour at least as long within
  // min_distance_px of its true position (+0.5 px for tracking error); the other drops are tracking losses.
  auto H_at = [](int k) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(0, 0, 0.3 * k);
    return PlaneHomography(T, kPlaneNormal, kPlaneDistanceM, Pinhole());
  };
  std::vector<TrackedFeature> before = r1.features;
  for (int k = 1; k <= 3; ++k) {
    const FeatureTrackResult r = tracker.Track(Frame(0.1 * k, Render(canvas, H_at(k), Pinhole())), Pinhole());
    ASSERT_TRUE(r.ok);
    ExpectSpread(r, 30.0);
    EXPECT_LE(r.stats.total, 150);
    const auto after = ById(r);
    int explained = 0;
    for (const TrackedFeature& f : before) {
      if (after.count(f.id)) continue;
      const Eigen::Vector2d truth = Apply(H_at(k) * H_at(k - 1).inverse(), f.pixel_px);
      explained += std::any_of(r.features.begin(), r.features.end(), [&](const TrackedFeature& g) {
        return g.track_length >= f.track_length + 1 && (g.pixel_px - truth).norm() < 30.0 + 0.5;
      });
    }
    std::printf("[ tracker ] zoom-out frame %d: previous %d, inliers %d, crowded %d (%d drops next to a longer "
                "track), new %d, total %d\n", k, r.stats.previous, r.stats.inliers, r.stats.rejected_crowded,
                explained, r.stats.new_features, r.stats.total);
    EXPECT_GT(r.stats.rejected_crowded, 5);
    EXPECT_GE(explained, r.stats.rejected_crowded);
    before = r.features;
  }
}

// Half the image at 3 % contrast: without a grid the strong half takes every corner (the quality level is relative
// to the strongest), a 2x2 grid gives every cell its share.
TEST(FeatureTracker, GridGivesLowContrastCellsFeatures) {
  cv::Mat grey = MakeTexture(5, cv::Size(640, 480));
  const cv::Mat faint = MakeTexture(6, cv::Size(320, 480), 0.03);
  faint.copyTo(grey(cv::Rect(320, 0, 320, 480)));
  cv::Mat image;
  cv::cvtColor(grey, image, cv::COLOR_GRAY2BGR);
  FeatureTrackerConfig gridded;
  gridded.grid_rows = gridded.grid_cols = 2;
  const FeatureTrackResult plain = FeatureTracker().Track(Frame(0.0, image), Pinhole());
  const FeatureTrackResult grid = FeatureTracker(gridded).Track(Frame(0.0, image), Pinhole());
  ASSERT_TRUE(plain.ok && grid.ok);
  const std::vector<int> c_plain = GridCounts(plain, 2, 2), c_grid = GridCounts(grid, 2, 2);
  std::printf("[ tracker ] faint right half: per 2x2 cell without grid %d %d %d %d, with grid %d %d %d %d\n",
              c_plain[0], c_plain[1], c_plain[2], c_plain[3], c_grid[0], c_grid[1], c_grid[2], c_grid[3]);
  EXPECT_LE(c_plain[1] + c_plain[3], 2);
  EXPECT_GE(std::min(c_grid[1], c_grid[3]), 20);
  ExpectSpread(grid, 30.0);
  EXPECT_EQ(grid.stats.total, 150);
}

// Six frames of the general motion, a Reset, two more: an id names one physical point for as long as it lives
// (its position follows the true homography from its first observation), its track length counts the frames, its
// velocity is the position change over the frame interval, and no id comes back once gone or is handed out twice.
TEST(FeatureTracker, IdsPersistAndAreNeverReused) {
  const cv::Mat canvas = MakeCanvas();
  FeatureTracker tracker;
  std::map<uint64_t, std::pair<int, Eigen::Vector2d>> first;  // id -> (frame, pixel) of its first observation
  std::map<uint64_t, TrackedFeature> last;                    // id -> its previous observation
  std::set<uint64_t> gone;
  uint64_t max_id_so_far = 0;
  int continued = 0;
  for (int k = 0; k < 8; ++k) {
    if (k == 6) tracker.Reset();
    const int pose = k < 6 ? k : k - 6;  // after the Reset the camera starts over: same images, new ids
    const FeatureTrackResult r = tracker.Track(Frame(0.1 * k, SequenceFrame(canvas, pose).image), Pinhole());
    ASSERT_TRUE(r.ok) << r.message;
    std::map<uint64_t, TrackedFeature> now;
    for (const TrackedFeature& f : r.features) {
      now[f.id] = f;
      EXPECT_EQ(gone.count(f.id), 0u) << "id " << f.id << " came back";
      if (!last.count(f.id)) {  // new: a fresh id above every earlier one
        EXPECT_EQ(f.track_length, 1);
        EXPECT_TRUE(f.velocity_pxps.isZero());
        if (k == 0) {
          EXPECT_LT(f.id, 150u);  // the first ids handed out: 0..149
        } else {
          EXPECT_GT(f.id, max_id_so_far);
        }
        EXPECT_EQ(first.count(f.id), 0u);
        first[f.id] = {pose, f.pixel_px};
        continue;
      }
      ++continued;
      const TrackedFeature& prev = last.at(f.id);
      EXPECT_EQ(f.track_length, prev.track_length + 1);
      EXPECT_NEAR((f.velocity_pxps - (f.pixel_px - prev.pixel_px) / 0.1).norm(), 0.0, 1e-9);
      const auto& [j, p] = first.at(f.id);
      const Eigen::Vector2d truth = Apply(SequenceHomography(pose) * SequenceHomography(j).inverse(), p);
      EXPECT_LT((f.pixel_px - truth).norm(), 1.0) << "id " << f.id << " drifted off its point";
    }
    for (const auto& [id, f] : last)
      if (!now.count(id)) gone.insert(id);
    for (const auto& [id, f] : now) max_id_so_far = std::max(max_id_so_far, id);
    EXPECT_EQ(tracker.next_id(), max_id_so_far + 1);
    if (k == 6) {
      EXPECT_EQ(r.stats.previous, 0);
    }
    last = std::move(now);
  }
  std::printf("[ tracker ] ids: %zu handed out over 8 frames (a Reset after 6), %zu ended, %d continuations\n",
              first.size(), gone.size(), continued);
  EXPECT_GT(gone.size(), 150u);  // the Reset ended 150, motion ended more: reuse would have been possible
  EXPECT_GT(continued, 600);
}

// A lens with strong barrel distortion (k1 = -0.28): the normalised coordinates reproject onto the measured pixels
// (cv::projectPoints) within 1e-3 px, and a rotation-hinted track of a distorted image lands where the rotation
// puts the point (so prediction and tracking both handle the distortion).
TEST(FeatureTracker, NormalisedCoordinatesUndistortThePixels) {
  CameraIntrinsics lens = Pinhole();
  lens.k1 = -0.28;
  lens.k2 = 0.07;
  lens.p1 = 2e-4;
  lens.p2 = -3e-4;
  const cv::Mat canvas = MakeCanvas();
  Pose3 T_2_1 = Pose3::Identity();
  T_2_1.linear() = ExpSO3(Eigen::Vector3d(0.02, 0.1, 0.01));  // ~6 deg
  const Eigen::Matrix3d H = PlaneHomography(T_2_1, kPlaneNormal, kPlaneDistanceM, lens);
  FeatureTracker tracker;
  const FeatureTrackResult r1 = tracker.Track(Frame(0.0, Render(canvas, Eigen::Matrix3d::Identity(), lens)), lens);
  const FeatureTrackResult r2 = tracker.Track(Frame(0.033, Render(canvas, H, lens)), lens,
                                              Eigen::Matrix3d(T_2_1.linear().transpose()));
  ASSERT_TRUE(r1.ok && r2.ok) << r2.message;
  const cv::Mat Kcv = (cv::Mat_<double>(3, 3) << lens.fx_px, 0, lens.cx_px, 0, lens.fy_px, lens.cy_px, 0, 0, 1);
  const std::vector<double> dist{lens.k1, lens.k2, lens.p1, lens.p2};
  double max_reprojection = 0.0, max_default = 0.0;
  for (const FeatureTrackResult* r : {&r1, &r2}) {
    std::vector<cv::Point3d> rays;
    std::vector<cv::Point2d> pixels, reprojected, opencv_default;
    for (const TrackedFeature& f : r->features) {
      rays.emplace_back(f.normalized.x(), f.normalized.y(), 1.0);
      pixels.emplace_back(f.pixel_px.x(), f.pixel_px.y());
    }
    cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), Kcv, dist, reprojected);
    cv::undistortPoints(pixels, opencv_default, Kcv, dist);
    for (size_t i = 0; i < pixels.size(); ++i) {
      max_reprojection = std::max(max_reprojection, cv::norm(reprojected[i] - pixels[i]));
      max_default = std::max(max_default, lens.fx_px * cv::norm(opencv_default[i] -
                                                                cv::Point2d(rays[i].x, rays[i].y)));
    }
  }
  std::vector<double> errors;
  const auto before = ById(r1);
  for (const TrackedFeature& f : r2.features) {
    if (!before.count(f.id)) continue;
    const Eigen::Vector3d ray = T_2_1.linear() * before.at(f.id).normalized.homogeneous();
    errors.push_back(lens.fx_px * (ray.hnormalized() - f.normalized).norm());
  }
  std::printf("[ tracker ] distortion: reprojection of the normalised coordinates max %.2e px (cv::undistortPoints "
              "with its default 5 iterations differs by up to %.3f px); %zu hinted tracks, rotation error median "
              "%.3f px, max %.3f px\n", max_reprojection, max_default, errors.size(), Median(errors),
              *std::max_element(errors.begin(), errors.end()));
  EXPECT_LT(max_reprojection, 1e-3);
  EXPECT_GE(errors.size(), 100u);
  EXPECT_LT(Median(errors), 0.3);
  EXPECT_LT(*std::max_element(errors.begin(), errors.end()), 1.5);
}

TEST(FeatureTracker, BadInputIsReportedAndLeavesTheStateAlone) {
  const cv::Mat canvas = MakeCanvas();
  const cv::Mat image = SequenceFrame(canvas, 0).image;
  FeatureTracker tracker;
  const FeatureTrackResult good = tracker.Track(Frame(0.0, image), Pinhole());
  ASSERT_TRUE(good.ok);
  auto expect_fail = [&](const FeatureTrackResult& r, const std::string& field) {
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.message.find(field), std::string::npos) << r.message;
    EXPECT_TRUE(r.features.empty());
  };
  expect_fail(tracker.Track(Frame(0.1, cv::Mat()), Pinhole()), "frame.image: empty");
  expect_fail(tracker.Track(Frame(0.1, image(cv::Rect(0, 0, 320, 240)).clone()), Pinhole()), "frame.image: size");
  cv::Mat as_float;
  image.convertTo(as_float, CV_32FC3);
  expect_fail(tracker.Track(Frame(0.1, as_float), Pinhole()), "frame.image: type");
  expect_fail(tracker.Track(Frame(std::nan(""), image), Pinhole()), "frame.t_s");
  expect_fail(tracker.Track(Frame(0.0, image), Pinhole()), "frame.t_s");  // not after the previous frame
  CameraIntrinsics no_focal = Pinhole();
  no_focal.fx_px = 0.0;
  expect_fail(tracker.Track(Frame(0.1, image), no_focal), "fx_px");
  expect_fail(tracker.Track(Frame(0.1, image), Pinhole(), Eigen::Matrix3d(2.0 * Eigen::Matrix3d::Identity())),
              "R_prev_cur");
  FeatureTrackerConfig bad;
  bad.max_features = 0;
  expect_fail(FeatureTracker(bad).Track(Frame(0.0, image), Pinhole()), "config: max_features");
  // Every field's check names it.
  std::string error;
  EXPECT_TRUE(FeatureTrackerConfig().Validate(&error));
  auto expect_invalid = [&](auto mutate, const std::string& field) {
    FeatureTrackerConfig c;
    mutate(c);
    EXPECT_FALSE(c.Validate(&error));
    EXPECT_EQ(error.rfind(field, 0), 0u) << error;
  };
  expect_invalid([](auto& c) { c.min_distance_px = -1; }, "min_distance_px");
  expect_invalid([](auto& c) { c.klt_window_px = 20; }, "klt_window_px");
  expect_invalid([](auto& c) { c.klt_max_level = -1; }, "klt_max_level");
  expect_invalid([](auto& c) { c.fb_threshold_px = 0; }, "fb_threshold_px");
  expect_invalid([](auto& c) { c.ransac_threshold_px = std::nan(""); }, "ransac_threshold_px");
  expect_invalid([](auto& c) { c.ransac_confidence = 1.0; }, "ransac_confidence");
  expect_invalid([](auto& c) { c.ransac_min_matches = 4; }, "ransac_min_matches");
  expect_invalid([](auto& c) { c.corner_quality = 0; }, "corner_quality");
  expect_invalid([](auto& c) { c.grid_rows = 0; }, "grid_rows");
  // The failures changed nothing: the next good frame continues the first frame's tracks.
  const FeatureTrackResult next = tracker.Track(SequenceFrame(canvas, 1), Pinhole());
  ASSERT_TRUE(next.ok) << next.message;
  EXPECT_EQ(next.stats.previous, good.stats.total);
  EXPECT_GE(next.stats.inliers, 130);
}

TEST(FeatureTracker, RansacIsSkippedWithFewMatches) {
  const cv::Mat canvas = MakeCanvas();
  FeatureTrackerConfig few;
  few.max_features = 6;
  FeatureTracker small(few), normal;
  for (int k = 0; k < 2; ++k) {
    const FeatureTrackResult a = small.Track(SequenceFrame(canvas, k), Pinhole());
    const FeatureTrackResult b = normal.Track(SequenceFrame(canvas, k), Pinhole());
    ASSERT_TRUE(a.ok && b.ok);
    EXPECT_FALSE(a.stats.ransac_ran);
    EXPECT_EQ(a.stats.rejected_ransac, 0);
    EXPECT_EQ(b.stats.ransac_ran, k == 1);
    if (k == 1) {
      EXPECT_EQ(a.stats.inliers, a.stats.tracked - a.stats.rejected_fb);
    }
    EXPECT_EQ(a.stats.total, 6);
  }
}

// Two trackers fed the same frames (two planes and the moving object, so RANSAC has outliers to find), interleaved,
// with OpenCV's global RNG re-seeded differently before each call: identical ids, positions (bit for bit), counts.
TEST(FeatureTracker, SameFramesGiveIdenticalTracks) {
  const TwoPlaneScene scene;
  FeatureTracker a, b;
  int ransac_rejections = 0;
  for (int k = 0; k < 5; ++k) {
    const cv::Mat image = WithObject(scene.View(SequencePose(k)), cv::Point(430 + 3 * k, 140 + 12 * k));
    cv::theRNG().state = 12345ULL + uint64_t(k);
    const FeatureTrackResult ra = a.Track(Frame(0.1 * k, image), Pinhole());
    cv::theRNG().state = 987654321ULL * uint64_t(k + 1);
    const FeatureTrackResult rb = b.Track(Frame(0.1 * k, image), Pinhole());
    ASSERT_TRUE(ra.ok && rb.ok);
    ASSERT_EQ(ra.features.size(), rb.features.size());
    for (size_t i = 0; i < ra.features.size(); ++i) {
      EXPECT_EQ(ra.features[i].id, rb.features[i].id);
      EXPECT_EQ(ra.features[i].pixel_px, rb.features[i].pixel_px);
      EXPECT_EQ(ra.features[i].normalized, rb.features[i].normalized);
      EXPECT_EQ(ra.features[i].track_length, rb.features[i].track_length);
    }
    EXPECT_EQ(ra.stats.rejected_ransac, rb.stats.rejected_ransac);
    EXPECT_EQ(ra.stats.rejected_fb, rb.stats.rejected_fb);
    EXPECT_EQ(ra.stats.ransac_ran, k > 0);
    ransac_rejections += ra.stats.rejected_ransac;
  }
  std::printf("[ tracker ] determinism: 5 frames identical; RANSAC rejected %d matches along the way\n",
              ransac_rejections);
}

}  // namespace
}  // namespace rotolidar::visual
