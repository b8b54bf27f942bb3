#include "core/loop/orb_features.hpp"

#include <opencv2/imgproc.hpp>

#include "core/util/validation.hpp"

namespace rotolidar::loop {

bool OrbConfig::Validate(std::string* error) const {
  if (max_features < 1) return FailValidation(error, "orb.max_features: must be >= 1");
  if (!(scale_factor > 1.0) || !(scale_factor <= 4.0))
    return FailValidation(error, "orb.scale_factor: must be in (1, 4]");
  if (pyramid_levels < 1 || pyramid_levels > 32) return FailValidation(error, "orb.pyramid_levels: must be in [1, 32]");
  if (patch_size_px < 2) return FailValidation(error, "orb.patch_size_px: must be >= 2");
  if (edge_threshold_px < 0) return FailValidation(error, "orb.edge_threshold_px: must be >= 0");
  if (fast_threshold < 1 || fast_threshold > 254)
    return FailValidation(error, "orb.fast_threshold: must be in [1, 254]");
  return true;
}

OrbExtractor::OrbExtractor(const OrbConfig& config) : config_(config) {
  if (!config_.Validate(&config_error_)) return;
  orb_ = cv::ORB::create(config_.max_features, static_cast<float>(config_.scale_factor), config_.pyramid_levels,
                         config_.edge_threshold_px, /*firstLevel=*/0, /*WTA_K=*/2, cv::ORB::HARRIS_SCORE,
                         config_.patch_size_px, config_.fast_threshold);
}

Status OrbExtractor::Extract(const cv::Mat& image, OrbFeatures* features) {
  features->keypoints.clear();
  features->descriptors.release();
  if (!config_error_.empty()) return Status::Error("ORB: invalid config: " + config_error_);
  if (image.empty()) return Status::Error("ORB: empty image");
  cv::Mat grey;
  if (image.type() == CV_8UC1) {
    grey = image;
  } else if (image.type() == CV_8UC3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    return Status::Error("ORB: image type " + std::to_string(image.type()) + " is neither CV_8UC1 nor CV_8UC3");
  }
  orb_->detectAndCompute(grey, cv::noArray(), features->keypoints, features->descriptors);
  if (features->keypoints.empty()) {
    features->descriptors.release();
    return Status::Ok();
  }
  if (features->descriptors.type() != CV_8U || features->descriptors.cols != kOrbDescriptorBytes ||
      features->descriptors.rows != static_cast<int>(features->keypoints.size())) {
    features->keypoints.clear();
    features->descriptors.release();
    return Status::Error("ORB: OpenCV returned descriptors of an unexpected shape");
  }
  return Status::Ok();
}

Status ExtractOrb(const cv::Mat& image, const OrbConfig& config, OrbFeatures* features) {
  OrbExtractor extractor(config);
  return extractor.Extract(image, features);
}

}  // namespace rotolidar::loop
