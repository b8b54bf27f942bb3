#include "core/backend/visual_landmarks.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"
#include "core/util/validation.hpp"
#include "core/visual/feature_depth.hpp"

namespace rotolidar {

struct VisualLandmarks::Observation {
  const double* pose = nullptr;  ///< the observing state's pose block (T_world_imu)
  Eigen::Vector2d normalized = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  ///< [1/s]
  double td_s = 0.0;                                   ///< the td `normalized` was moved with [s]
  std::unique_ptr<ceres::CostFunction> factor;  ///< null for the anchor's own observation
};

struct VisualLandmarks::Landmark {
  uint64_t feature_id = 0;
  double inverse_depth = 0.0;  ///< the parameter block [1/m]
  bool lidar_depth = false;    ///< the depth came from the LiDAR
  bool triangulated = false;
  bool in_problem = false;     ///< its factors were in the last problem
  std::unique_ptr<ceres::CostFunction> depth_prior;  ///< from the LiDAR depth (null without one)
  std::vector<Observation> observations;  ///< observations[0] is the anchor's
  const double* anchor() const { return observations.front().pose; }
};

bool VisualWindowConfig::Validate(std::string* error) const {
  auto positive = [](double x) { return x > 0.0 && std::isfinite(x); };
  if (!positive(pixel_sigma_px)) return FailValidation(error, "visual.pixel_sigma_px must be > 0");
  if (!positive(huber_sigmas)) return FailValidation(error, "visual.huber_sigmas must be > 0");
  if (min_observations < 2) return FailValidation(error, "visual.min_observations must be >= 2");
  if (!positive(min_depth_m)) return FailValidation(error, "visual.min_depth_m must be > 0");
  if (!(max_depth_m > min_depth_m) || !std::isfinite(max_depth_m))
    return FailValidation(error, "visual.max_depth_m must be > min_depth_m");
  if (!positive(max_reprojection_px)) return FailValidation(error, "visual.max_reprojection_px must be > 0");
  if (!(initial_depth_m >= min_depth_m && initial_depth_m <= max_depth_m))
    return FailValidation(error, "visual.initial_depth_m must lie in [min_depth_m, max_depth_m]");
  if (max_landmarks < 1) return FailValidation(error, "visual.max_landmarks must be >= 1");
  if (!(max_pixel_sigma_px >= pixel_sigma_px) || !std::isfinite(max_pixel_sigma_px))
    return FailValidation(error, "visual.max_pixel_sigma_px must be >= pixel_sigma_px");
  if (!(sigma_smoothing > 0.0 && sigma_smoothing <= 1.0))
    return FailValidation(error, "visual.sigma_smoothing must lie in (0, 1]");
  if (min_residuals_for_sigma < 1) return FailValidation(error, "visual.min_residuals_for_sigma must be >= 1");
  if (!positive(time_offset_prior_sigma_s)) return FailValidation(error, "visual.time_offset_prior_sigma_s must be > 0");
  if (!positive(lidar_depth_sigma_m)) return FailValidation(error, "visual.lidar_depth_sigma_m must be > 0");
  if (!(lidar_depth_sigma_per_m >= 0.0) || !std::isfinite(lidar_depth_sigma_per_m))
    return FailValidation(error, "visual.lidar_depth_sigma_per_m must be >= 0");
  return true;
}

namespace {

/// Huber(delta) on residuals whitened at sigma instead of nominal_sigma, for residuals whitened at nominal_sigma:
/// with k = nominal_sigma / sigma, rho(k^2 s) = k^2 Huber_{delta / k}(s) (both branches), i.e. a ScaledLoss.
std::unique_ptr<ceres::LossFunction> HuberAtSigma(double delta, double nominal_sigma, double sigma) {
  if (sigma == nominal_sigma) return std::make_unique<ceres::HuberLoss>(delta);
  const double k = nominal_sigma / sigma;
  return std::make_unique<ceres::ScaledLoss>(new ceres::HuberLoss(delta / k), k * k, ceres::TAKE_OWNERSHIP);
}

/// (x - x0) / sigma on one scalar block: the time offset's prior around the calibrated value, a LiDAR depth's
/// prior on an inverse depth.
class ScalarPrior final : public ceres::SizedCostFunction<1, 1> {
 public:
  ScalarPrior(double x0, double sigma) : x0_(x0), sigma_(sigma) {}
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    residuals[0] = (parameters[0][0] - x0_) / sigma_;
    if (jacobians != nullptr && jacobians[0] != nullptr) jacobians[0][0] = 1.0 / sigma_;
    return true;
  }

 private:
  double x0_, sigma_;
};

}  // namespace

VisualLandmarks::VisualLandmarks(const VisualWindowConfig& config, const Pose3& T_imu_cam, double focal_px)
    : config_(config), T_imu_cam_(T_imu_cam), focal_px_(focal_px) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  ROTOLIDAR_CHECK(focal_px > 0.0 && std::isfinite(focal_px), "VisualLandmarks: focal_px must be > 0");
  sqrt_information_ = ReprojectionSqrtInformation(focal_px, config.pixel_sigma_px);
  sigma_px_ = config.pixel_sigma_px;
  td_prior_ = std::make_unique<ScalarPrior>(0.0, config.time_offset_prior_sigma_s);
}

VisualLandmarks::~VisualLandmarks() = default;

void VisualLandmarks::Clear() {
  landmarks_.clear();
  sigma_px_ = config_.pixel_sigma_px;
  stats_.live = stats_.in_problem = stats_.with_lidar_depth = stats_.factors = 0;
}

void VisualLandmarks::AddObservations(const double* pose, const std::vector<VisualObservation>& observations) {
  for (const VisualObservation& o : observations) {
    if (!o.normalized.allFinite()) {
      ++stats_.skipped_total;
      continue;
    }
    auto it = landmarks_.find(o.feature_id);
    if (it == landmarks_.end()) {
      if (int(landmarks_.size()) >= config_.max_landmarks) {
        ++stats_.skipped_total;
        continue;
      }
      auto l = std::make_unique<Landmark>();
      l->feature_id = o.feature_id;
      const bool has_depth = std::isfinite(o.lidar_depth_m) && o.lidar_depth_m >= config_.min_depth_m &&
                             o.lidar_depth_m <= config_.max_depth_m;
      l->lidar_depth = has_depth;
      l->inverse_depth = 1.0 / (has_depth ? o.lidar_depth_m : config_.initial_depth_m);
      if (has_depth) {
        const double d = o.lidar_depth_m;
        const double sigma_d = config_.lidar_depth_sigma_m + config_.lidar_depth_sigma_per_m * d;
        l->depth_prior = std::make_unique<ScalarPrior>(1.0 / d, sigma_d / (d * d));
      }
      l->observations.push_back({pose, o.normalized, o.velocity_normalized_ps, o.td_s, nullptr});
      landmarks_.emplace(o.feature_id, std::move(l));
      continue;
    }
    Landmark& l = *it->second;
    if (l.observations.back().pose == pose) continue;  // one observation per state
    l.observations.push_back({pose, o.normalized, o.velocity_normalized_ps, o.td_s, nullptr});
    l.observations.back().factor = MakeFactor(l, l.observations.back());
    if (!l.lidar_depth && !l.triangulated) Triangulate(&l);
  }
}

int VisualLandmarks::AddToProblem(ceres::Problem* problem) {
  if (!loss_ || loss_sigma_px_ != sigma_px_) {  // the previous problem (its only user) is gone
    loss_ = HuberAtSigma(config_.huber_sigmas, config_.pixel_sigma_px, sigma_px_);
    loss_sigma_px_ = sigma_px_;
  }
  int factors = 0, in_problem = 0;
  for (auto& [id, l] : landmarks_) {
    l->in_problem = int(l->observations.size()) >= config_.min_observations;
    if (!l->in_problem) continue;
    ++in_problem;
    problem->AddParameterBlock(&l->inverse_depth, kInverseDepthBlockSize);
    for (Observation& o : l->observations) {
      if (!o.factor) continue;
      problem->AddResidualBlock(o.factor.get(), loss_.get(), FactorBlocks(*l, o));
      ++factors;
    }
    if (l->lidar_depth && config_.fix_lidar_depth) problem->SetParameterBlockConstant(&l->inverse_depth);
    else if (l->depth_prior) problem->AddResidualBlock(l->depth_prior.get(), nullptr, &l->inverse_depth);
  }
  if (config_.estimate_time_offset && factors > 0) problem->AddResidualBlock(td_prior_.get(), nullptr, td_s_);
  stats_.factors = factors;
  stats_.in_problem = in_problem;
  return factors;
}

Eigen::Vector2d VisualLandmarks::Corrected(const Observation& o) const {
  if (!config_.estimate_time_offset) return o.normalized;
  return o.normalized - (td_s_[0] - o.td_s) * o.velocity;
}

std::unique_ptr<ceres::CostFunction> VisualLandmarks::MakeFactor(const Landmark& l, const Observation& o) const {
  const Observation& a = l.observations.front();
  ReprojectionMeasurement m;
  m.anchor_normalized = a.normalized;
  m.normalized = o.normalized;
  m.sqrt_information = sqrt_information_;
  if (!config_.estimate_time_offset) return std::make_unique<ReprojectionFactor>(m, T_imu_cam_);
  const FeatureMotion motion{a.velocity, o.velocity, a.td_s, o.td_s};
  return std::make_unique<ReprojectionTimeOffsetFactor>(m, motion, T_imu_cam_);
}

std::vector<double*> VisualLandmarks::FactorBlocks(Landmark& l, const Observation& o) {
  std::vector<double*> blocks = {const_cast<double*>(l.anchor()), const_cast<double*>(o.pose), &l.inverse_depth};
  if (config_.estimate_time_offset) blocks.push_back(td_s_);
  return blocks;
}

bool VisualLandmarks::InFrontEverywhere(const Landmark& l) const {
  const Pose3 T_a = UnpackImuPose(l.anchor());
  const Eigen::Vector2d u_a = Corrected(l.observations.front());
  for (const Observation& o : l.observations)
    if (!LandmarkInFront(T_a, UnpackImuPose(o.pose), T_imu_cam_, u_a, l.inverse_depth, config_.min_depth_m))
      return false;
  return true;
}

double VisualLandmarks::ReprojectionErrorsPx(const Landmark& l, std::vector<double>* errors_px) const {
  const Pose3 T_a = UnpackImuPose(l.anchor());
  const Eigen::Vector2d u_a = Corrected(l.observations.front());
  double worst = 0.0;
  for (const Observation& o : l.observations) {
    if (!o.factor) continue;  // the anchor's own observation reprojects exactly
    const Eigen::Vector2d u = PredictNormalized(T_a, UnpackImuPose(o.pose), T_imu_cam_, u_a, l.inverse_depth);
    const double e = focal_px_ * (u - Corrected(o)).norm();
    errors_px->push_back(e);
    worst = std::max(worst, e);
  }
  return worst;
}

int VisualLandmarks::RejectOutliers() {
  std::vector<double> residuals_px;
  int dropped = 0;
  for (auto it = landmarks_.begin(); it != landmarks_.end();) {
    const Landmark& l = *it->second;
    const bool bad = l.in_problem && (!std::isfinite(l.inverse_depth) || !InFrontEverywhere(l) ||
                                      !(ReprojectionErrorsPx(l, &residuals_px) <= config_.max_reprojection_px));
    if (bad) {
      it = landmarks_.erase(it);
      ++dropped;
    } else {
      ++it;
    }
  }
  stats_.rejected_total += dropped;
  UpdateSigma(&residuals_px);
  return dropped;
}

// Residuals of every factor of the last solve (outliers included: the median ignores up to half of them). The
// median of |r| for a 2-D isotropic Gaussian r (a Rayleigh variable) is sigma sqrt(2 ln 2) = 1.1774 sigma.
void VisualLandmarks::UpdateSigma(std::vector<double>* residuals_px) {
  if (residuals_px->empty()) return;
  auto mid = residuals_px->begin() + residuals_px->size() / 2;
  std::nth_element(residuals_px->begin(), mid, residuals_px->end());
  stats_.residual_median_px = *mid;
  if (!config_.adaptive_sigma || int(residuals_px->size()) < config_.min_residuals_for_sigma) return;
  const double estimate_px = std::max(*mid / std::sqrt(2.0 * std::log(2.0)), 1e-3);
  const double a = config_.sigma_smoothing;
  const double smoothed = std::exp((1.0 - a) * std::log(sigma_px_) + a * std::log(estimate_px));
  sigma_px_ = std::clamp(smoothed, config_.pixel_sigma_px, config_.max_pixel_sigma_px);
}

std::vector<MarginalizationTerm> VisualLandmarks::TermsOf(const double* pose, std::vector<const double*>* dropped) {
  std::vector<MarginalizationTerm> terms;
  for (auto& [id, l] : landmarks_) {
    if (l->anchor() != pose || !l->in_problem) continue;
    const BlockRef depth{&l->inverse_depth, BlockKind::kVector, kInverseDepthBlockSize};
    for (Observation& o : l->observations) {
      if (!o.factor) continue;
      std::vector<BlockRef> blocks = {BlockRef{const_cast<double*>(l->anchor()), BlockKind::kPose, kImuPoseBlockSize},
                                      BlockRef{const_cast<double*>(o.pose), BlockKind::kPose, kImuPoseBlockSize},
                                      depth};
      if (config_.estimate_time_offset) blocks.push_back(BlockRef{td_s_, BlockKind::kVector, kTimeOffsetBlockSize});
      terms.push_back({o.factor.get(), loss_.get(), std::move(blocks)});
    }
    if (l->depth_prior && !config_.fix_lidar_depth) terms.push_back({l->depth_prior.get(), nullptr, {depth}});
    dropped->push_back(&l->inverse_depth);
  }
  return terms;
}

void VisualLandmarks::RemoveState(const double* pose) {
  for (auto it = landmarks_.begin(); it != landmarks_.end();) {
    Landmark& l = *it->second;
    if (l.anchor() == pose) {
      it = landmarks_.erase(it);
      continue;
    }
    // Not its anchor: a later observation (anchors are the oldest observation, so this only happens when states
    // leave out of order, e.g. a reset); drop it.
    l.observations.erase(std::remove_if(l.observations.begin(), l.observations.end(),
                                        [&](const Observation& o) { return o.pose == pose; }),
                         l.observations.end());
    ++it;
  }
}

// A landmark without a LiDAR depth takes the depth of a triangulation over its observations at the current pose
// estimates (VINS-Mono's triangulate), once the rays open past the parallax gate; until then the initial depth.
void VisualLandmarks::Triangulate(Landmark* l) const {
  std::vector<Eigen::Vector2d> xy;
  std::vector<Pose3> T_world_cam;
  for (const Observation& o : l->observations) {
    xy.push_back(Corrected(o));
    T_world_cam.push_back(UnpackImuPose(o.pose) * T_imu_cam_);
  }
  visual::TriangulationConfig config;
  config.focal_length_px = focal_px_;
  config.max_reprojection_rms_px = config_.max_reprojection_px;
  config.min_depth_m = config_.min_depth_m;
  const visual::Triangulation t = visual::TriangulateFeature(xy, T_world_cam, config);
  if (!t.valid || t.depth_anchor_m > config_.max_depth_m) return;
  l->inverse_depth = 1.0 / t.depth_anchor_m;
  l->triangulated = true;
}

VisualLandmarkStats VisualLandmarks::stats() const {
  VisualLandmarkStats s = stats_;
  s.sigma_px = sigma_px_;
  s.time_offset_s = td_s_[0];
  s.live = int(landmarks_.size());
  s.with_lidar_depth = int(std::count_if(landmarks_.begin(), landmarks_.end(),
                                         [](const auto& kv) { return kv.second->lidar_depth; }));
  return s;
}

std::vector<std::pair<uint64_t, Eigen::Vector3d>> VisualLandmarks::LandmarkPositions() const {
  std::vector<std::pair<uint64_t, Eigen::Vector3d>> out;
  for (const auto& [id, l] : landmarks_) {
    if (!l->in_problem || !(l->inverse_depth > 0.0)) continue;
    const Eigen::Vector2d u_a = Corrected(l->observations.front());
    const Eigen::Vector3d p_cam(u_a.x() / l->inverse_depth, u_a.y() / l->inverse_depth, 1.0 / l->inverse_depth);
    out.emplace_back(id, UnpackImuPose(l->anchor()) * (T_imu_cam_ * p_cam));
  }
  return out;
}

}  // namespace rotolidar
