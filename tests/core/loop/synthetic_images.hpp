#pragma once
// Synthetic textured images for place-recognition tests: a "place" is a deterministic 640x480 grey image drawn from
// a stream named after it; a "view" is that place rotated, shifted, re-lit and noisy.
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/util/rng.hpp"

namespace rotolidar::loop::test_util {

inline int UniformInt(RandomStream* rng, int lo, int hi) { return lo + int(rng->NextU64() % uint64_t(hi - lo + 1)); }

// A 640x480 "place": a smooth multi-scale noise background under grey rectangles, circles and lines, all drawn
// from a stream named after the place, so every place has its own arrangement of corners and blobs for ORB.
inline cv::Mat MakePlace(const std::string& name) {
  RandomStream rng(2024, name);
  // Background: random grey cells of 80, 32 and 16 px, cubic-upsampled and summed.
  cv::Mat image(480, 640, CV_32F, cv::Scalar(0));
  for (int cell : {80, 32, 16}) {
    cv::Mat grid(480 / cell + 1, 640 / cell + 1, CV_32F);
    for (int r = 0; r < grid.rows; ++r)
      for (int c = 0; c < grid.cols; ++c) grid.at<float>(r, c) = float(rng.Uniform() * 255.0 - 127.5);
    cv::Mat up;
    cv::resize(grid, up, cv::Size(grid.cols * cell, grid.rows * cell), 0, 0, cv::INTER_CUBIC);
    image += up(cv::Rect(0, 0, 640, 480)) * 0.5;
  }
  image.convertTo(image, CV_8U, 1.0, 128.0);
  auto point = [&] { return cv::Point{UniformInt(&rng, 0, 639), UniformInt(&rng, 0, 479)}; };
  for (int i = 0; i < 30; ++i) {
    const cv::Point a = point();
    const cv::Point size{UniformInt(&rng, 10, 100), UniformInt(&rng, 10, 100)};
    cv::rectangle(image, a, a + size, cv::Scalar(UniformInt(&rng, 0, 255)), cv::FILLED);
  }
  for (int i = 0; i < 20; ++i) {  // one draw per statement: the order of a call's arguments is unspecified
    const cv::Point c = point();
    const int radius_px = UniformInt(&rng, 5, 40);
    cv::circle(image, c, radius_px, cv::Scalar(UniformInt(&rng, 0, 255)), cv::FILLED);
  }
  for (int i = 0; i < 15; ++i) {
    const cv::Point a = point(), b = point();
    const int grey = UniformInt(&rng, 0, 255);
    cv::line(image, a, b, cv::Scalar(grey), UniformInt(&rng, 1, 4));
  }
  return image;
}

// Another view of a place: rotated by angle_deg about the centre, shifted by (dx, dy) px, grey levels
// gain * g + bias, plus Gaussian pixel noise (sigma 3 grey levels).
inline cv::Mat MakeView(const cv::Mat& place, double dx, double dy, double angle_deg, double gain, double bias,
                 const std::string& noise_name) {
  cv::Mat warp = cv::getRotationMatrix2D(cv::Point2f(320, 240), angle_deg, 1.0);
  warp.at<double>(0, 2) += dx;
  warp.at<double>(1, 2) += dy;
  cv::Mat view;
  cv::warpAffine(place, view, warp, place.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  view.convertTo(view, CV_32F, gain, bias);
  RandomStream rng(2024, noise_name);
  for (int r = 0; r < view.rows; ++r)
    for (int c = 0; c < view.cols; ++c) view.at<float>(r, c) += float(3.0 * rng.Normal());
  view.convertTo(view, CV_8U);  // saturates
  return view;
}

}  // namespace rotolidar::loop::test_util
