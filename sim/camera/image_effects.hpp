#pragma once
// What happens to the rendered light on its way to the PNG: motion blur over the exposure and the image sensor
// (exposure, shot and read noise, full-well clipping, gain, gamma, 8-bit quantisation). docs/camera_model.md.
//
// Determinism: the noise of frame k comes from its own RandomStream, seeded from the run seed, the stream name
// "camera.noise" and k, split per image row; no result depends on the number of threads.
#include <cstdint>
#include <functional>
#include <vector>

#include <opencv2/core.hpp>

#include "core/types/calib.hpp"
#include "core/types/geometry.hpp"
#include "sim/camera/camera_model.hpp"

namespace rotolidar::sim {

/// Linear light as a renderer produces it, before the sensor. Rows top to bottom, pixel (u, v) at v * width + u.
struct RadianceImage {
  int width = 0, height = 0;
  /// width * height * 3 (RGB) values: the radiance a Lambert surface of albedo a sends back under irradiance E
  /// is a * E, with the scene's lights in [0, 1] (a white wall under unit light = 1; 1 fills the sensor's well
  /// at the default exposure).
  std::vector<float> rgb;
  /// width * height: depth of what each pixel sees, along the optical axis (z) [m]; 0 = sky (no surface).
  std::vector<float> depth_m;
  void Resize(int w, int h);
};

/// Runs fn(row_begin, row_end) over [0, rows) in fixed blocks of `block_rows` rows, on `threads` threads (the
/// calling thread is one of them). The blocks do not depend on `threads`. fn must be safe to call concurrently
/// on disjoint blocks.
void ParallelRows(int rows, int threads, int block_rows, const std::function<void(int, int)>& fn);

/// The camera's motion over one exposure, relative to its pose at mid-exposure: p_mid = T_mid_start * p_start.
struct ExposureMotion {
  Pose3 T_mid_start = Pose3::Identity();
  Pose3 T_mid_end = Pose3::Identity();
};

/// Velocity blur: each pixel averages the sharp image along the path its scene point takes through the image
/// during the exposure (the pixel's ray at its depth, moved by the camera motion; sky at infinity, rotation only),
/// with one tap per <= 0.5 px of path (at most 33). Approximations: depth is the mid-exposure depth, the path is
/// linear from start to middle and middle to end, dynamic objects' own motion is not blurred, and what the
/// mid-exposure image does not see (disocclusions) is not filled in. Exact for pure rotation.
/// Returns the largest path half-length [px] over the image.
double ApplyVelocityBlur(const rotolidar::CameraIntrinsics& k, const PixelRayTable& rays, const ExposureMotion& motion,
                         const RadianceImage& sharp, int threads, RadianceImage* blurred);

/// The seed of frame `frame_index`'s sensor noise: RandomStream(run_seed, "camera.noise")'s seed mixed with it.
uint64_t FrameNoiseSeed(uint64_t run_seed, long frame_index);

/// The sensor: for each pixel and colour channel, signal e = radiance * quantum_rate_e_per_s * exposure_s [e-],
/// measured e' = e + sqrt(e + read_noise_e^2) N(0, 1) (Poisson shot noise in its normal limit, plus read noise),
/// clipped to [0, full_well_e]; DN = gain * 255 * e' / full_well_e clipped to [0, 255], then
/// 255 (DN / 255)^(1 / gamma), rounded to 8 bits. Normal draws come from a 65,536-entry inverse-CDF table
/// (exact to the table's step; tails at +-4.2 sigma). Writes *bgr8 (CV_8UC3, OpenCV's BGR order).
void ExposeSensor(const CameraConfig& config, const RadianceImage& radiance, uint64_t noise_seed, int threads,
                  cv::Mat* bgr8);

}  // namespace rotolidar::sim
