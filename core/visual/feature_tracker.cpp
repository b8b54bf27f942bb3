#include "core/visual/feature_tracker.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "core/util/validation.hpp"

namespace rotolidar::visual {
namespace {

using Clock = std::chrono::steady_clock;

bool Positive(double v) { return std::isfinite(v) && v > 0.0; }

cv::Mat CameraMatrix(const CameraIntrinsics& c) {
  return (cv::Mat_<double>(3, 3) << c.fx_px, 0.0, c.cx_px, 0.0, c.fy_px, c.cy_px, 0.0, 0.0, 1.0);
}

cv::Mat DistCoeffs(const CameraIntrinsics& c) { return (cv::Mat_<double>(1, 4) << c.k1, c.k2, c.p1, c.p2); }

/// Undistorted normalised coordinates of measured pixels. Up to 20 iterations, stopping at 1e-6 px of reprojection
/// error: OpenCV's default 5 leave up to 0.74 px near the corners of a lens with k1 = -0.28 (the tests measure it).
std::vector<Eigen::Vector2d> Undistort(const std::vector<cv::Point2f>& pixels, const CameraIntrinsics& c) {
  std::vector<Eigen::Vector2d> out(pixels.size());
  if (pixels.empty()) return out;
  std::vector<cv::Point2d> in(pixels.begin(), pixels.end()), norm;
  cv::undistortPoints(in, norm, CameraMatrix(c), DistCoeffs(c), cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 1e-6));
  for (size_t i = 0; i < norm.size(); ++i) out[i] = Eigen::Vector2d(norm[i].x, norm[i].y);
  return out;
}

/// The measured pixel of a normalised point (radial-tangential model, as cv::projectPoints).
cv::Point2f Distort(const Eigen::Vector2d& n, const CameraIntrinsics& c) {
  const double x = n.x(), y = n.y(), r2 = x * x + y * y;
  const double radial = 1.0 + c.k1 * r2 + c.k2 * r2 * r2;
  const double xd = x * radial + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y;
  return cv::Point2f(static_cast<float>(c.fx_px * xd + c.cx_px), static_cast<float>(c.fy_px * yd + c.cy_px));
}

/// Where a static point at normalised `from` (camera frame a) is seen in camera frame b under a pure rotation
/// R_a_b (p_a = R_a_b p_b): b_b ~ R_a_b^T b_a, re-distorted. A bearing turned behind the camera keeps `fallback`.
std::vector<cv::Point2f> PredictByRotation(const std::vector<Eigen::Vector2d>& from, const Eigen::Matrix3d& R_a_b,
                                           const CameraIntrinsics& c, const std::vector<cv::Point2f>& fallback) {
  std::vector<cv::Point2f> out(fallback);
  for (size_t i = 0; i < from.size(); ++i) {
    const Eigen::Vector3d b = R_a_b.transpose() * from[i].homogeneous();
    if (b.z() > 1e-3) out[i] = Distort(b.hnormalized(), c);
  }
  return out;
}

bool InBorder(const cv::Point2f& p, const cv::Size& size, double border) {
  return std::isfinite(p.x) && std::isfinite(p.y) && p.x >= border && p.y >= border &&
         p.x <= size.width - 1 - border && p.y <= size.height - 1 - border;
}

bool CheckIntrinsics(const CameraIntrinsics& c, std::string* error) {
  if (c.width_px <= 0 || c.height_px <= 0) return FailValidation(error, "intrinsics.width_px/height_px: must be > 0");
  if (!Positive(c.fx_px) || !Positive(c.fy_px)) return FailValidation(error, "intrinsics.fx_px/fy_px: must be > 0");
  if (!std::isfinite(c.cx_px) || !std::isfinite(c.cy_px))
    return FailValidation(error, "intrinsics.cx_px/cy_px: not finite");
  if (!std::isfinite(c.k1) || !std::isfinite(c.k2) || !std::isfinite(c.p1) || !std::isfinite(c.p2))
    return FailValidation(error, "intrinsics.k1/k2/p1/p2: not finite");
  return true;
}

bool CheckFrame(const CameraFrame& f, const CameraIntrinsics& c, std::string* error) {
  if (!std::isfinite(f.t_s)) return FailValidation(error, "frame.t_s: not finite");
  if (f.image.empty()) return FailValidation(error, "frame.image: empty");
  if (f.image.type() != CV_8UC3 && f.image.type() != CV_8UC1)
    return FailValidation(error, "frame.image: type must be CV_8UC3 (BGR8) or CV_8UC1");
  if (f.image.cols != c.width_px || f.image.rows != c.height_px)
    return FailValidation(error, "frame.image: size " + std::to_string(f.image.cols) + "x" +
                                     std::to_string(f.image.rows) + " differs from intrinsics.width_px x height_px " +
                                     std::to_string(c.width_px) + "x" + std::to_string(c.height_px));
  return true;
}

bool CheckRotation(const std::optional<Eigen::Matrix3d>& R, std::string* error) {
  if (!R) return true;
  if (!R->allFinite() || !(*R * R->transpose()).isIdentity(1e-6) || std::abs(R->determinant() - 1.0) > 1e-6)
    return FailValidation(error, "R_prev_cur: not a rotation matrix");
  return true;
}

/// The feature observed again at `pixel` / `normalized`, dt_s after its previous observation.
TrackedFeature Advance(TrackedFeature f, const Eigen::Vector2d& pixel, const Eigen::Vector2d& normalized, double dt_s) {
  f.velocity_pxps = (pixel - f.pixel_px) / dt_s;
  f.velocity_normalized_ps = (normalized - f.normalized) / dt_s;
  f.pixel_px = pixel;
  f.normalized = normalized;
  ++f.track_length;
  return f;
}

double SquaredDistance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return (a - b).squaredNorm(); }

}  // namespace

bool FeatureTrackerConfig::Validate(std::string* error) const {
  if (max_features < 1) return FailValidation(error, "max_features: must be >= 1");
  if (!std::isfinite(min_distance_px) || min_distance_px < 0.0)
    return FailValidation(error, "min_distance_px: must be finite and >= 0");
  if (klt_window_px < 3 || klt_window_px % 2 == 0) return FailValidation(error, "klt_window_px: must be odd and >= 3");
  if (klt_max_level < 0 || klt_max_level > 8) return FailValidation(error, "klt_max_level: must be in [0, 8]");
  if (klt_max_iterations < 1) return FailValidation(error, "klt_max_iterations: must be >= 1");
  if (!Positive(klt_epsilon_px)) return FailValidation(error, "klt_epsilon_px: must be > 0");
  if (!std::isfinite(border_px) || border_px < 0.0) return FailValidation(error, "border_px: must be finite and >= 0");
  if (!Positive(fb_threshold_px)) return FailValidation(error, "fb_threshold_px: must be > 0");
  if (!Positive(ransac_threshold_px)) return FailValidation(error, "ransac_threshold_px: must be > 0");
  if (!(ransac_confidence > 0.0 && ransac_confidence < 1.0))
    return FailValidation(error, "ransac_confidence: must be in (0, 1)");
  if (ransac_max_iterations < 1) return FailValidation(error, "ransac_max_iterations: must be >= 1");
  if (ransac_min_matches < 5) return FailValidation(error, "ransac_min_matches: must be >= 5");
  if (!(corner_quality > 0.0 && corner_quality <= 1.0))
    return FailValidation(error, "corner_quality: must be in (0, 1]");
  if (corner_block_px < 1) return FailValidation(error, "corner_block_px: must be >= 1");
  if (grid_rows < 1 || grid_cols < 1) return FailValidation(error, "grid_rows/grid_cols: must be >= 1");
  if (detect_level < 0 || detect_level > klt_max_level)
    return FailValidation(error, "detect_level: must be in [0, klt_max_level]");
  return true;
}

FeatureTracker::FeatureTracker(const FeatureTrackerConfig& config) : config_(config) {
  config_.Validate(&config_error_);
}

void FeatureTracker::Reset() {
  features_.clear();
  pyramid_.clear();
}

FeatureTrackResult FeatureTracker::Track(const CameraFrame& frame, const CameraIntrinsics& intrinsics,
                                         const std::optional<Eigen::Matrix3d>& R_prev_cur) {
  const auto t0 = Clock::now();
  FeatureTrackResult result;
  result.t_s = frame.t_s;
  std::string error;
  // Each Check* fills `error` when it fails; the chain stops at the first failure.
  if (!config_error_.empty()) error = "config: " + config_error_;
  else if (CheckIntrinsics(intrinsics, &error) && CheckFrame(frame, intrinsics, &error) &&
           CheckRotation(R_prev_cur, &error) && !pyramid_.empty() && !(frame.t_s > t_prev_s_))
    error = "frame.t_s: not later than the previous frame's";
  if (!error.empty()) {
    result.message = error;
    return result;
  }
  cv::Mat grey;
  if (frame.image.channels() == 3) cv::cvtColor(frame.image, grey, cv::COLOR_BGR2GRAY);
  else grey = frame.image.clone();
  std::vector<cv::Mat> pyramid;
  const cv::Size window(config_.klt_window_px, config_.klt_window_px);
  cv::buildOpticalFlowPyramid(grey, pyramid, window, config_.klt_max_level, true);
  std::vector<TrackedFeature> features;
  if (!pyramid_.empty() && pyramid_[0].size() == grey.size())
    features = TrackPrevious(pyramid, intrinsics, R_prev_cur, frame.t_s - t_prev_s_, &result.stats);
  Thin(&features, &result.stats);
  AddNewFeatures(grey, pyramid, intrinsics, &features, &result.stats);
  std::sort(features.begin(), features.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  features_ = features;
  pyramid_ = std::move(pyramid);
  t_prev_s_ = frame.t_s;
  result.ok = true;
  result.features = std::move(features);
  result.stats.total = static_cast<int>(result.features.size());
  result.stats.time_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  return result;
}

std::vector<TrackedFeature> FeatureTracker::TrackPrevious(const std::vector<cv::Mat>& pyramid,
                                                          const CameraIntrinsics& intrinsics,
                                                          const std::optional<Eigen::Matrix3d>& R_prev_cur,
                                                          double dt_s, FeatureTrackStats* stats) const {
  stats->previous = static_cast<int>(features_.size());
  if (features_.empty()) return {};
  std::vector<cv::Point2f> prev_px;
  std::vector<Eigen::Vector2d> prev_norm;
  for (const TrackedFeature& f : features_) {
    prev_px.emplace_back(static_cast<float>(f.pixel_px.x()), static_cast<float>(f.pixel_px.y()));
    prev_norm.push_back(f.normalized);
  }
  // Forward: from the hint's prediction, or in place.
  std::vector<cv::Point2f> cur_px =
      R_prev_cur ? PredictByRotation(prev_norm, *R_prev_cur, intrinsics, prev_px) : prev_px;
  const std::vector<uchar> forward_ok = Klt(pyramid_, pyramid, prev_px, &cur_px);
  std::vector<int> index;  // into features_
  std::vector<cv::Point2f> fwd;
  for (size_t i = 0; i < prev_px.size(); ++i) {
    if (!forward_ok[i] || !InBorder(cur_px[i], pyramid[0].size(), config_.border_px)) continue;
    index.push_back(static_cast<int>(i));
    fwd.push_back(cur_px[i]);
  }
  stats->tracked = static_cast<int>(index.size());
  // Backward: from the hint's inverse prediction, or in place; never from the answer.
  const std::vector<Eigen::Vector2d> fwd_norm = Undistort(fwd, intrinsics);
  std::vector<cv::Point2f> back =
      R_prev_cur ? PredictByRotation(fwd_norm, R_prev_cur->transpose(), intrinsics, fwd) : fwd;
  const std::vector<uchar> backward_ok = Klt(pyramid, pyramid_, fwd, &back);
  std::vector<int> kept;  // into index
  std::vector<Eigen::Vector2d> match_prev, match_cur;
  for (size_t k = 0; k < index.size(); ++k) {
    const cv::Point2f miss = back[k] - prev_px[index[k]];
    if (!backward_ok[k] || !(std::hypot(miss.x, miss.y) <= config_.fb_threshold_px)) continue;
    kept.push_back(static_cast<int>(k));
    match_prev.push_back(prev_norm[index[k]]);
    match_cur.push_back(fwd_norm[k]);
  }
  stats->rejected_fb = stats->tracked - static_cast<int>(kept.size());
  std::vector<TrackedFeature> out;
  for (int m : RansacInliers(match_prev, match_cur, intrinsics, stats)) {
    const int k = kept[m];
    out.push_back(Advance(features_[index[k]], Eigen::Vector2d(fwd[k].x, fwd[k].y), fwd_norm[k], dt_s));
  }
  stats->inliers = static_cast<int>(out.size());
  return out;
}

std::vector<uchar> FeatureTracker::Klt(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                       const std::vector<cv::Point2f>& from_px,
                                       std::vector<cv::Point2f>* to_px) const {
  std::vector<uchar> status;
  if (from_px.empty()) return status;
  std::vector<float> error;
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, config_.klt_max_iterations,
                                  config_.klt_epsilon_px);
  cv::calcOpticalFlowPyrLK(from, to, from_px, *to_px, status, error,
                           cv::Size(config_.klt_window_px, config_.klt_window_px), config_.klt_max_level, criteria,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  return status;
}

std::vector<int> FeatureTracker::RansacInliers(const std::vector<Eigen::Vector2d>& prev_normalized,
                                               const std::vector<Eigen::Vector2d>& cur_normalized,
                                               const CameraIntrinsics& intrinsics, FeatureTrackStats* stats) const {
  std::vector<int> all(prev_normalized.size());
  std::iota(all.begin(), all.end(), 0);
  stats->ransac_ran = false;
  if (static_cast<int>(all.size()) < config_.ransac_min_matches) return all;
  std::vector<cv::Point2d> p1, p2;
  for (size_t i = 0; i < all.size(); ++i) {
    p1.emplace_back(prev_normalized[i].x(), prev_normalized[i].y());
    p2.emplace_back(cur_normalized[i].x(), cur_normalized[i].y());
  }
  const double threshold = config_.ransac_threshold_px / (0.5 * (intrinsics.fx_px + intrinsics.fy_px));
  std::vector<uchar> mask;
  const cv::Mat E = cv::findEssentialMat(p1, p2, cv::Mat::eye(3, 3, CV_64F), cv::RANSAC, config_.ransac_confidence,
                                         threshold, config_.ransac_max_iterations, mask);
  if (E.empty() || mask.size() != all.size()) return all;  // no model: keep all, ransac_ran stays false
  stats->ransac_ran = true;
  std::vector<int> inliers;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) inliers.push_back(static_cast<int>(i));
  stats->rejected_ransac = static_cast<int>(all.size() - inliers.size());
  return inliers;
}

void FeatureTracker::Thin(std::vector<TrackedFeature>* features, FeatureTrackStats* stats) const {
  std::vector<TrackedFeature> sorted = *features;
  std::sort(sorted.begin(), sorted.end(), [](const TrackedFeature& a, const TrackedFeature& b) {
    return a.track_length != b.track_length ? a.track_length > b.track_length : a.id < b.id;
  });
  const double min_d2 = config_.min_distance_px * config_.min_distance_px;
  features->clear();
  for (const TrackedFeature& f : sorted) {
    const bool crowded = std::any_of(features->begin(), features->end(), [&](const TrackedFeature& g) {
      return SquaredDistance(f.pixel_px, g.pixel_px) < min_d2;
    });
    if (crowded) continue;
    if (static_cast<int>(features->size()) >= config_.max_features) break;
    features->push_back(f);
  }
  stats->rejected_crowded = static_cast<int>(sorted.size() - features->size());
}

void FeatureTracker::AddNewFeatures(const cv::Mat& grey, const std::vector<cv::Mat>& pyramid,
                                    const CameraIntrinsics& intrinsics, std::vector<TrackedFeature>* features,
                                    FeatureTrackStats* stats) {
  const int budget = config_.max_features - static_cast<int>(features->size());
  if (budget <= 0) return;
  // Detection runs on pyramid level L (scale 2^-L); the mask and the regions are drawn at that level.
  const int level = 2 * config_.detect_level < int(pyramid.size()) ? config_.detect_level : 0;
  const cv::Mat& image = level == 0 ? grey : pyramid[2 * level];
  const float scale = static_cast<float>(1 << level);
  const double min_d2 = config_.min_distance_px * config_.min_distance_px;
  const int radius = static_cast<int>(std::ceil(config_.min_distance_px / scale));
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(255));
  for (const TrackedFeature& f : *features)
    cv::circle(mask, cv::Point(cvRound(f.pixel_px.x() / scale), cvRound(f.pixel_px.y() / scale)), radius,
               cv::Scalar(0), cv::FILLED);
  std::vector<cv::Point2f> added;
  // One detection in `roi` (full-image pixels) of up to `quota` corners; each must keep min_distance_px from every
  // feature so far (the mask's discs are rasterised, so the distance is checked exactly as well).
  auto detect = [&](const cv::Rect& roi_full, int quota) {
    quota = std::min(quota, budget - static_cast<int>(added.size()));
    if (quota <= 0) return;
    const cv::Rect roi = cv::Rect(roi_full.x >> level, roi_full.y >> level, roi_full.width >> level,
                                  roi_full.height >> level) & cv::Rect(0, 0, image.cols, image.rows);
    std::vector<cv::Point2f> corners;  // a quarter more than the quota: some fail the exact checks at full scale
    const int ask = level == 0 ? quota : quota + quota / 4 + 4;
    // A cell alone (a copy, not a view): on a view OpenCV's corner filter reads the pixels around the cell, and a
    // strong edge just outside it would set the cell's quality threshold (seen: faint cells left empty).
    const bool whole = roi.size() == image.size();
    cv::goodFeaturesToTrack(whole ? image : image(roi).clone(), corners, ask, config_.corner_quality,
                            config_.min_distance_px / scale, mask(roi), config_.corner_block_px);
    if (corners.empty()) return;
    for (cv::Point2f& c : corners) c = (c + cv::Point2f(float(roi.x), float(roi.y))) * scale;
    if (level > 0)
      cv::cornerSubPix(grey, corners, cv::Size(2, 2), cv::Size(-1, -1),
                       cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 10, 0.03));
    const size_t limit = added.size() + size_t(quota);
    for (cv::Point2f c : corners) {
      if (added.size() >= limit) break;
      if (!InBorder(c, grey.size(), config_.border_px)) continue;
      const Eigen::Vector2d p(c.x, c.y);
      auto near = [&](const Eigen::Vector2d& q) { return SquaredDistance(p, q) < min_d2; };
      if (std::any_of(features->begin(), features->end(), [&](const auto& f) { return near(f.pixel_px); }) ||
          std::any_of(added.begin(), added.end(), [&](const auto& a) { return near(Eigen::Vector2d(a.x, a.y)); }))
        continue;
      added.push_back(c);
      cv::circle(mask, cv::Point(cvRound(c.x / scale), cvRound(c.y / scale)), radius, cv::Scalar(0), cv::FILLED);
    }
  };
  const int cells = config_.grid_rows * config_.grid_cols;
  if (cells > 1) {
    for (int r = 0; r < config_.grid_rows; ++r)
      for (int c = 0; c < config_.grid_cols; ++c) {
        const int x0 = grey.cols * c / config_.grid_cols, x1 = grey.cols * (c + 1) / config_.grid_cols;
        const int y0 = grey.rows * r / config_.grid_rows, y1 = grey.rows * (r + 1) / config_.grid_rows;
        const cv::Rect cell(x0, y0, x1 - x0, y1 - y0);
        const auto in_cell = std::count_if(features->begin(), features->end(), [&](const TrackedFeature& f) {
          return cell.contains(cv::Point2d(f.pixel_px.x(), f.pixel_px.y()));
        });
        detect(cell, std::max(1, config_.max_features / cells) - static_cast<int>(in_cell));
      }
  }
  detect(cv::Rect(0, 0, grey.cols, grey.rows), budget);
  const std::vector<Eigen::Vector2d> normalized = Undistort(added, intrinsics);
  for (size_t i = 0; i < added.size(); ++i) {
    TrackedFeature f;
    f.id = next_id_++;
    f.pixel_px = Eigen::Vector2d(added[i].x, added[i].y);
    f.normalized = normalized[i];
    features->push_back(f);
  }
  stats->new_features = static_cast<int>(added.size());
}

}  // namespace rotolidar::visual
