#pragma once
// ORB features (Rublee et al., "ORB: an efficient alternative to SIFT or SURF", ICCV 2011) for the visual stage of
// loop closure: OpenCV's cv::ORB with the settings ORB-SLAM2 uses (1000 features, 8 pyramid levels, scale 1.2),
// whose 32-byte binary descriptors feed the bag-of-words vocabulary (core/loop/vocabulary.hpp).
//
// Thread-safety: ExtractOrb is re-entrant (it makes its own cv::ORB per call); an OrbExtractor is not (cv::ORB
// keeps scratch buffers), use one per thread.
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

#include "core/util/status.hpp"

namespace rotolidar::loop {

/// Bytes per ORB descriptor (256 bits).
inline constexpr int kOrbDescriptorBytes = 32;

/// cv::ORB settings. The defaults are ORB-SLAM2's for a 640x480 camera (Mur-Artal & Tardos, T-RO 2017): 1000
/// features spread over an 8-level pyramid with scale factor 1.2, FAST threshold 20.
struct OrbConfig {
  int max_features = 1000;     ///< at most this many keypoints per image (the strongest by Harris score)
  double scale_factor = 1.2;   ///< pyramid decimation ratio, > 1
  int pyramid_levels = 8;      ///< >= 1
  int edge_threshold_px = 31;  ///< border without features [px]; >= patch_size_px / 2 keeps descriptors inside
  int patch_size_px = 31;      ///< descriptor patch edge [px]
  int fast_threshold = 20;     ///< FAST intensity threshold [grey levels, 0..255]

  bool Validate(std::string* error) const;
};

/// Keypoints [px, in the input image] and their descriptors: row i of `descriptors` (CV_8U, kOrbDescriptorBytes
/// columns) belongs to keypoints[i]. Both are empty when the image has no features.
struct OrbFeatures {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

/// Reusable extractor (keeps one cv::ORB).
class OrbExtractor {
 public:
  /// The config must be valid (Validate); an invalid one makes every Extract fail with the validation message.
  explicit OrbExtractor(const OrbConfig& config = OrbConfig());

  /// Detects and describes ORB features in `image` (CV_8UC1 grey or CV_8UC3 BGR, as cv::imread loads). Fails,
  /// naming the problem, on an empty image, another pixel type or an invalid config; *features is then cleared.
  Status Extract(const cv::Mat& image, OrbFeatures* features);

  const OrbConfig& config() const { return config_; }

 private:
  OrbConfig config_;
  std::string config_error_;  ///< empty when config_ is valid
  cv::Ptr<cv::ORB> orb_;
};

/// One-shot convenience: OrbExtractor(config).Extract(image, features).
Status ExtractOrb(const cv::Mat& image, const OrbConfig& config, OrbFeatures* features);

}  // namespace rotolidar::loop
