#pragma once
// Synthetic scenes for the feature tracker's tests: a randomly textured plane (or two) rendered at known camera
// poses, so the true motion of every pixel is a homography.
#include <algorithm>
#include <cstdint>
#include <map>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/types/geometry.hpp"
#include "core/visual/feature_tracker.hpp"

namespace rotolidar::visual::tracker_test {


constexpr int kMargin = 240;  // the texture canvas extends this far [px] beyond the first view on every side

inline CameraIntrinsics Pinhole() { return CameraIntrinsics(); }  // 640x480, f = 462 px, no distortion

inline Eigen::Matrix3d K(const CameraIntrinsics& c) {
  Eigen::Matrix3d k;
  k << c.fx_px, 0, c.cx_px, 0, c.fy_px, c.cy_px, 0, 0, 1;
  return k;
}

// A random grey texture (fixed seed): a smooth background of random 40 px cells under random rectangles and discs,
// blurred (sigma 1.2 px) so that the bilinear resampling of the views stays close to the true warp (the errors the
// tests measure include it).
inline cv::Mat MakeTexture(uint64_t seed, cv::Size size, double contrast = 1.0) {
  cv::RNG rng(seed);
  cv::Mat cells(size.height / 40 + 2, size.width / 40 + 2, CV_8UC1);
  rng.fill(cells, cv::RNG::UNIFORM, 60, 196);
  cv::Mat tex;
  cv::resize(cells, tex, cv::Size(cells.cols * 40, cells.rows * 40), 0, 0, cv::INTER_CUBIC);
  tex = tex(cv::Rect(0, 0, size.width, size.height)).clone();
  const int shapes = size.area() / 400;
  for (int i = 0; i < shapes; ++i) {
    const cv::Point p{rng.uniform(0, size.width), rng.uniform(0, size.height)};
    const cv::Scalar grey(rng.uniform(0, 256));
    if (i % 2) cv::rectangle(tex, p, p + cv::Point{rng.uniform(4, 30), rng.uniform(4, 30)}, grey, cv::FILLED);
    else cv::circle(tex, p, rng.uniform(3, 16), grey, cv::FILLED);
  }
  cv::GaussianBlur(tex, tex, cv::Size(0, 0), 1.2);
  if (contrast != 1.0) tex.convertTo(tex, CV_8U, contrast, 128.0 * (1.0 - contrast));
  return tex;
}

inline cv::Mat MakeCanvas(uint64_t seed = 7) {
  return MakeTexture(seed, cv::Size(640 + 2 * kMargin, 480 + 2 * kMargin));
}

// Homography from view-1 pixels to view-k pixels for the plane n^T X1 = d (view-1 camera frame) and the camera
// motion T_k_1 (X_k = R X_1 + t): H = K (R + t n^T / d) K^-1.
inline Eigen::Matrix3d PlaneHomography(const Pose3& T_k_1, const Eigen::Vector3d& n, double d,
                                       const CameraIntrinsics& c) {
  return K(c) * (T_k_1.linear() + T_k_1.translation() * n.transpose() / d) * K(c).inverse();
}

inline Eigen::Vector2d Apply(const Eigen::Matrix3d& H, const Eigen::Vector2d& p) {
  return (H * p.homogeneous()).hnormalized();
}

// True when p lies at least `margin` px inside a 640x480 image (11: a whole 21 px KLT window).
inline bool Inside(const Eigen::Vector2d& p, double margin = 11.0) {
  return p.x() >= margin && p.y() >= margin && p.x() <= 639 - margin && p.y() <= 479 - margin;
}

// View k of the canvas, BGR8: view-1 pixel u shows canvas pixel u + margin; view k is view 1 moved by H_k_1.
// With distortion, every measured pixel is undistorted to find the ideal pixel it sees.
inline cv::Mat Render(const cv::Mat& canvas, const Eigen::Matrix3d& H_k_1, const CameraIntrinsics& c) {
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

inline CameraFrame Frame(double t_s, cv::Mat image) { return CameraFrame{t_s, std::move(image)}; }

// A general motion in front of a tilted plane 3 m away: ~6 px of translation and ~5 px of rotation flow per frame.
inline const Eigen::Vector3d kPlaneNormal = Eigen::Vector3d(0.15, -0.1, 1.0).normalized();
constexpr double kPlaneDistanceM = 3.0;
inline Pose3 SequencePose(int k) {
  Pose3 T = Pose3::Identity();
  T.linear() = ExpSO3(k * Eigen::Vector3d(0.004, -0.01, 0.003));
  T.translation() = k * Eigen::Vector3d(0.04, -0.015, 0.05);
  return T;
}
inline Eigen::Matrix3d SequenceHomography(int k) {
  return PlaneHomography(SequencePose(k), kPlaneNormal, kPlaneDistanceM, Pinhole());
}
inline CameraFrame SequenceFrame(const cv::Mat& canvas, int k) {
  return Frame(0.1 * k, Render(canvas, SequenceHomography(k), Pinhole()));
}

inline std::map<uint64_t, TrackedFeature> ById(const FeatureTrackResult& r) {
  std::map<uint64_t, TrackedFeature> m;
  for (const TrackedFeature& f : r.features) m[f.id] = f;
  return m;
}

inline double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}


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
inline cv::Mat WithObject(cv::Mat image, const cv::Point& at) {
  cv::Mat object_bgr;
  cv::cvtColor(MakeTexture(99, cv::Size(180, 180)), object_bgr, cv::COLOR_GRAY2BGR);
  object_bgr.copyTo(image(cv::Rect(at, object_bgr.size())));
  return image;
}

// An independently moving object (its own texture, 12 px down between the frames) in front of the two planes while
// the camera moves sideways: its features break the epipolar constraint by ~12 px and RANSAC must drop them.

inline void ExpectSpread(const FeatureTrackResult& r, double min_distance_px) {
  for (size_t i = 0; i < r.features.size(); ++i)
    for (size_t j = i + 1; j < r.features.size(); ++j)
      EXPECT_GE((r.features[i].pixel_px - r.features[j].pixel_px).norm(), min_distance_px)
          << r.features[i].id << " " << r.features[j].id;
}

inline std::vector<int> GridCounts(const FeatureTrackResult& r, int rows, int cols) {
  std::vector<int> counts(rows * cols, 0);
  for (const TrackedFeature& f : r.features)
    ++counts[int(f.pixel_px.y() * rows / 480) * cols + int(f.pixel_px.x() * cols / 640)];
  return counts;
}


}  // namespace rotolidar::visual::tracker_test
