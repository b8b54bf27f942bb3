#include "core/pipeline/vacated_screen.hpp"

#include <limits>
#include <string>

#include "core/registration/kd_tree.hpp"
#include "core/util/log.hpp"

namespace rotolidar {

VacatedScreen::VacatedScreen(const FreeSpaceConfig& config, const Eigen::Vector3d& origin_base)
    : config_(config),
      origin_base_(origin_base.cast<float>()) {
  std::string why;
  ROTOLIDAR_CHECK(config_.Validate(&why), why);
}

void VacatedScreen::Vacated(Seconds t_s, const Pose3& T_world_base, const RangeImage& image,
                            std::vector<float>* xyz) const {
  const Pose3 T_base_world = T_world_base.inverse();
  const PlacedImage placed{&image, T_base_world.linear().cast<float>(),
                           T_base_world.translation().cast<float>() - origin_base_};
  const float margin = float(config_.margin_m), margin_per_m = float(config_.margin_per_m);
  xyz->clear();
  for (const Recent& recent : recent_) {
    const double age_s = t_s - recent.t_s;
    if (age_s < config_.vacated_min_age_s || age_s > config_.vacated_max_age_s) continue;
    JudgePoints(placed, recent.p_world, margin, margin_per_m, std::numeric_limits<float>::infinity(),
                [&](size_t i, RangeImage::Verdict verdict) {
                  if (verdict != RangeImage::Verdict::kSeenThrough) return;
                  const auto p = recent.p_world.col(Eigen::Index(i));
                  xyz->insert(xyz->end(), {p.x(), p.y(), p.z()});
                });
  }
}

VacatedResult VacatedScreen::Flag(Seconds t_s, const Pose3& T_world_base_guess, const RangeImage& image,
                                  const Eigen::Matrix3Xf& features_base, std::vector<uint8_t>* flagged) const {
  VacatedResult result;
  flagged->assign(size_t(features_base.cols()), 0);
  std::vector<float> xyz;
  Vacated(t_s, T_world_base_guess, image, &xyz);
  result.vacated = xyz.size() / 3;
  if (result.vacated == 0) return result;
  KdTree3f tree;
  tree.Build(xyz);
  const Eigen::Matrix3f R = T_world_base_guess.linear().cast<float>();
  const Eigen::Vector3f t = T_world_base_guess.translation().cast<float>();
  const float r2 = float(config_.vacated_radius_m * config_.vacated_radius_m);
  int index;
  float sq_dist;
  for (Eigen::Index i = 0; i < features_base.cols(); ++i) {
    const Eigen::Vector3f p = R * features_base.col(i) + t;
    const float q[3] = {p.x(), p.y(), p.z()};
    if (tree.Nearest(q, 1, &index, &sq_dist, r2) == 1) {
      (*flagged)[size_t(i)] = 1;
      ++result.flagged;
    }
  }
  if (double(result.flagged) > config_.vacated_max_share * double(features_base.cols())) {
    result.valve = true;
    flagged->assign(flagged->size(), 0);
  }
  return result;
}

void VacatedScreen::Remember(Seconds t_s, const Pose3& T_world_base, const Eigen::Matrix3Xf& features_base) {
  Recent recent{t_s, Eigen::Matrix3Xf()};
  recent.p_world.noalias() = T_world_base.linear().cast<float>() * features_base;
  recent.p_world.colwise() += T_world_base.translation().cast<float>();
  recent_.push_back(std::move(recent));
  while (!recent_.empty() && recent_.front().t_s < t_s - config_.vacated_max_age_s) recent_.pop_front();
}

}  // namespace rotolidar
