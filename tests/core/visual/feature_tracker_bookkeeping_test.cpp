// The feature tracker's bookkeeping on synthetic images: ids, undistortion, bad input, RANSAC's skip rule and
// determinism (the accuracy tests: feature_tracker_test.cpp).
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
#include "tests/core/visual/tracker_test_scenes.hpp"

namespace rotolidar::visual {
namespace {

using namespace tracker_test;

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
