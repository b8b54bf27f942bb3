#pragma once
// The twin's RGB camera (docs/camera_model.md): configuration, and the lens model shared by both renderers.
//
// Lens: pinhole + radial-tangential distortion with OpenCV's conventions (cv::projectPoints, cv::undistortPoints;
// the same four coefficients as core's CameraIntrinsics / calib.yaml): for a point p_cam (optical frame: z forward,
// x right, y down), x = X/Z, y = Y/Z, r2 = x^2 + y^2,
//   xd = x (1 + k1 r2 + k2 r2^2) + 2 p1 x y + p2 (r2 + 2 x^2)
//   yd = y (1 + k1 r2 + k2 r2^2) + p1 (r2 + 2 y^2) + 2 p2 x y
//   u = fx xd + cx,  v = fy yd + cy        [px; pixel centres at integer coordinates, (0, 0) = top-left pixel]
// The renderers cast one ray per pixel centre through the inverse of this map (PixelRayTable).
//
// Defaults: D435i-like colour camera, 640 x 480 at 30 Hz, fx = fy = 462 px: 69.4 deg horizontal field of view.
// (The D435i's quoted 69 x 42 deg is its 16:9 mode; with square pixels a 4:3 image at 69.4 deg across is
// 54.9 deg high.) A mild distortion a calibrated D435i colour lens shows (set k1..p2 to 0 for a pure pinhole).
//
// Units: SI (s, m), pixels [px], electrons [e-], 8-bit digital numbers [DN].
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/types/calib.hpp"
#include "core/util/status.hpp"

namespace YAML {
class Emitter;
class Node;
}  // namespace YAML

namespace rotolidar::sim {

/// Which engine draws the scene (docs/camera_model.md compares them).
enum class CameraRendererKind {
  kEmbree,  ///< ray casting through the lens model (sim/camera/embree_camera.hpp)
  kOsmesa,  ///< MuJoCo + OSMesa pinhole render, then cv::remap to the distorted image (osmesa_camera.hpp)
};

/// How motion during the exposure blurs the image.
enum class MotionBlurKind {
  kNone,       ///< the scene at the mid-exposure pose only
  kVelocity,   ///< one render + per-pixel blur along the image motion the true camera motion causes (depth aware)
  kSubframes,  ///< blur_subframes renders spread over the exposure, averaged (exact; blur_subframes x slower)
};

/// The words of the kinds in YAML and on the command line (core/io/yaml_fields.hpp finds them by argument-dependent
/// lookup), and lookups both ways ("?" for a value outside the enum).
const std::vector<std::pair<const char*, CameraRendererKind>>& EnumWords(CameraRendererKind*);
const std::vector<std::pair<const char*, MotionBlurKind>>& EnumWords(MotionBlurKind*);
bool ParseCameraRendererKind(const std::string& name, CameraRendererKind* kind);  ///< "embree" | "osmesa"
const char* CameraRendererName(CameraRendererKind kind);
bool ParseMotionBlurKind(const std::string& name, MotionBlurKind* kind);  ///< "none" | "velocity" | "subframes"
const char* MotionBlurName(MotionBlurKind kind);

/// One RGB camera: lens, timing, sensor and rendering. Plain struct with defaults; YAML in camera_yaml.cpp.
struct CameraConfig {
  bool enabled = true;     ///< the sim writes camera.csv + camera/ (and truth/cam.tum)
  double rate_hz = 30.0;   ///< frame rate; frame k is exposed around t_k = (k + 0.5) / rate_hz
  // Lens (written to calib.yaml `camera:`).
  int width_px = 640;
  int height_px = 480;
  double fx_px = 462.0, fy_px = 462.0;
  double cx_px = 320.0, cy_px = 240.0;
  double k1 = -0.04, k2 = 0.015, p1 = 4e-4, p2 = -3e-4;
  // Timing.
  double exposure_s = 0.010;  ///< integration time of every row
  double readout_s = 0.0;     ///< rolling shutter: first row to last row; 0 = global shutter
  // Sensor (image_effects.hpp): electrons = radiance * quantum_rate_e_per_s * exposure_s, Poisson shot noise,
  // Gaussian read noise, clipped at the full well; DN = gain * 255 * electrons / full_well_e, then gamma.
  double quantum_rate_e_per_s = 6.0e5;  ///< e-/s at unit rendered radiance (radiance 1 fills the well in 10 ms)
  double full_well_e = 6000.0;          ///< saturation [e-]
  double read_noise_e = 3.0;            ///< read noise sigma [e-]
  double gain = 1.0;                    ///< digital gain (> 0)
  double gamma = 1.0;                   ///< output = 255 (DN / 255)^(1 / gamma); 1 = linear like the renderers
  // Rendering.
  CameraRendererKind renderer = CameraRendererKind::kEmbree;  ///< why not osmesa: docs/camera_model.md
  MotionBlurKind motion_blur = MotionBlurKind::kVelocity;
  int blur_subframes = 4;     ///< renders per frame for kSubframes (>= 2)
  int threads = 2;            ///< worker threads for rendering, blur and noise (the bytes do not depend on it)
  bool shadows = true;        ///< embree: lights with cast_shadow cast shadows (osmesa: never)
  double max_range_m = 500.0; ///< farther surfaces are sky

  /// Checks every field (names it on failure): sizes, focal lengths, an invertible lens over the whole image,
  /// exposure + readout within one frame period, sensor values.
  bool Validate(std::string* error) const;
  /// The lens and rate as calib.yaml holds them (core's CameraIntrinsics).
  rotolidar::CameraIntrinsics Intrinsics() const;
  double frame_period_s() const { return 1.0 / rate_hz; }
};

/// Normalised image coordinates (x = X/Z, y = Y/Z) -> distorted normalised coordinates.
Eigen::Vector2d DistortNormalized(const rotolidar::CameraIntrinsics& k, const Eigen::Vector2d& xy);

/// p_cam [m] (z > 0) -> pixel [px], as cv::projectPoints with rvec = tvec = 0 and (k1, k2, p1, p2).
Eigen::Vector2d ProjectToPixel(const rotolidar::CameraIntrinsics& k, const Eigen::Vector3d& p_cam);

/// Pixel [px] -> undistorted normalised coordinates (Newton's method on the distortion map, converged to
/// 1e-12). Returns false when it does not converge (the pixel lies outside the lens's invertible region).
bool UndistortPixel(const rotolidar::CameraIntrinsics& k, const Eigen::Vector2d& uv_px, Eigen::Vector2d* xy);

/// For every pixel centre (row-major, width x height), its undistorted normalised coordinates (x, y): the
/// ray through the pixel is (x, y, 1) in the camera frame. Requires a valid lens (CameraConfig::Validate).
struct PixelRayTable {
  int width = 0, height = 0;
  std::vector<Eigen::Vector2f> xy;  ///< width * height entries
  const Eigen::Vector2f& at(int u, int v) const { return xy[static_cast<std::size_t>(v * width + u)]; }
};
PixelRayTable MakePixelRayTable(const rotolidar::CameraIntrinsics& k);

/// YAML (sim/camera/camera_yaml.cpp), the `camera:` section of a sim config. Keys (all optional; absent keys keep
/// *config's values): enabled, rate_hz, width_px, height_px, fx_px, fy_px, cx_px, cy_px, k1, k2, p1, p2,
/// exposure_s, readout_s, quantum_rate_e_per_s, full_well_e, read_noise_e, gain, gamma, renderer, motion_blur,
/// blur_subframes, threads, shadows, max_range_m. Unknown keys, unreadable and invalid values give an error naming
/// file:line and the field (*config untouched then); a missing node changes nothing.
Status ParseCameraConfig(const std::string& file, const YAML::Node& node, CameraConfig* config);
void EmitCameraConfig(YAML::Emitter& out, const CameraConfig& config);

}  // namespace rotolidar::sim
