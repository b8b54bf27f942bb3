// The camera's configuration checks and its lens model (OpenCV's radial-tangential convention).
#include "sim/camera/camera_model.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

/// Distortion of normalised coordinates and its 2x2 Jacobian.
Eigen::Vector2d Distort(const rotolidar::CameraIntrinsics& k, const Eigen::Vector2d& p, Eigen::Matrix2d* J) {
  const double x = p.x(), y = p.y(), r2 = x * x + y * y;
  const double radial = 1.0 + k.k1 * r2 + k.k2 * r2 * r2;
  const Eigen::Vector2d d(x * radial + 2.0 * k.p1 * x * y + k.p2 * (r2 + 2.0 * x * x),
                          y * radial + k.p1 * (r2 + 2.0 * y * y) + 2.0 * k.p2 * x * y);
  if (J) {
    const double dr = 2.0 * (k.k1 + 2.0 * k.k2 * r2);  // d radial / d(x or y), divided by x or y
    (*J)(0, 0) = radial + x * x * dr + 2.0 * k.p1 * y + 6.0 * k.p2 * x;
    (*J)(0, 1) = x * y * dr + 2.0 * k.p1 * x + 2.0 * k.p2 * y;
    (*J)(1, 0) = x * y * dr + 2.0 * k.p1 * x + 2.0 * k.p2 * y;
    (*J)(1, 1) = radial + y * y * dr + 6.0 * k.p1 * y + 2.0 * k.p2 * x;
  }
  return d;
}

/// True when the radial part r (1 + k1 r^2 + k2 r^4) grows monotonically on [0, r_max].
bool RadialMonotonic(const rotolidar::CameraIntrinsics& k, double r_max) {
  for (int i = 0; i <= 200; ++i) {
    const double r = r_max * i / 200.0, r2 = r * r;
    if (1.0 + 3.0 * k.k1 * r2 + 5.0 * k.k2 * r2 * r2 <= 0.0) return false;
  }
  return true;
}

/// Every border pixel undistorts and projects back within 1e-6 px; *r_max = the largest undistorted radius.
bool LensInvertibleOnBorder(const rotolidar::CameraIntrinsics& k, double* r_max) {
  *r_max = 0.0;
  const auto check = [&](double u, double v) {
    Eigen::Vector2d xy;
    if (!UndistortPixel(k, Eigen::Vector2d(u, v), &xy)) return false;
    *r_max = std::max(*r_max, xy.norm());
    return (ProjectToPixel(k, Eigen::Vector3d(xy.x(), xy.y(), 1.0)) - Eigen::Vector2d(u, v)).norm() < 1e-6;
  };
  const double w = k.width_px - 0.5, h = k.height_px - 0.5;  // the outer pixel edges
  for (int i = 0; i <= 64; ++i) {
    const double s = i / 64.0;
    if (!check(-0.5 + s * (w + 0.5), -0.5) || !check(-0.5 + s * (w + 0.5), h) || !check(-0.5, -0.5 + s * (h + 0.5)) ||
        !check(w, -0.5 + s * (h + 0.5)))
      return false;
  }
  return true;
}

}  // namespace

const std::vector<std::pair<const char*, CameraRendererKind>>& EnumWords(CameraRendererKind*) {
  static const std::vector<std::pair<const char*, CameraRendererKind>> words{
      {"embree", CameraRendererKind::kEmbree}, {"osmesa", CameraRendererKind::kOsmesa}};
  return words;
}

const std::vector<std::pair<const char*, MotionBlurKind>>& EnumWords(MotionBlurKind*) {
  static const std::vector<std::pair<const char*, MotionBlurKind>> words{
      {"none", MotionBlurKind::kNone}, {"velocity", MotionBlurKind::kVelocity},
      {"subframes", MotionBlurKind::kSubframes}};
  return words;
}

bool ParseCameraRendererKind(const std::string& name, CameraRendererKind* kind) {
  for (const auto& [word, k] : EnumWords(kind))
    if (name == word) return *kind = k, true;
  return false;
}

const char* CameraRendererName(CameraRendererKind kind) {
  for (const auto& [word, k] : EnumWords(&kind))
    if (kind == k) return word;
  return "?";
}

bool ParseMotionBlurKind(const std::string& name, MotionBlurKind* kind) {
  for (const auto& [word, k] : EnumWords(kind))
    if (name == word) return *kind = k, true;
  return false;
}

const char* MotionBlurName(MotionBlurKind kind) {
  for (const auto& [word, k] : EnumWords(&kind))
    if (kind == k) return word;
  return "?";
}

rotolidar::CameraIntrinsics CameraConfig::Intrinsics() const {
  rotolidar::CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.fx_px = fx_px;
  k.fy_px = fy_px;
  k.cx_px = cx_px;
  k.cy_px = cy_px;
  k.k1 = k1;
  k.k2 = k2;
  k.p1 = p1;
  k.p2 = p2;
  k.rate_hz = rate_hz;
  return k;
}

bool CameraConfig::Validate(std::string* error) const {
  const auto fail = [&](const std::string& what) {
    if (error) *error = "camera." + what;
    return false;
  };
  const auto finite_positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!(finite_positive(rate_hz) && rate_hz <= 1000.0)) return fail("rate_hz must be in (0, 1000]");
  if (width_px < 8 || height_px < 8 || width_px > 8192 || height_px > 8192)
    return fail("width_px, height_px must be in [8, 8192]");
  if (!finite_positive(fx_px) || !finite_positive(fy_px)) return fail("fx_px, fy_px must be > 0");
  if (!std::isfinite(cx_px) || !std::isfinite(cy_px)) return fail("cx_px, cy_px must be finite");
  for (double d : {k1, k2, p1, p2})
    if (!std::isfinite(d) || std::abs(d) > 10.0) return fail("k1, k2, p1, p2 must be finite with |value| <= 10");
  double r_max = 0.0;
  if (!LensInvertibleOnBorder(Intrinsics(), &r_max) || !RadialMonotonic(Intrinsics(), 1.05 * r_max))
    return fail("k1, k2, p1, p2: the distortion is not invertible over the image (it folds back)");
  if (!finite_positive(exposure_s)) return fail("exposure_s must be > 0");
  if (!(readout_s >= 0.0 && std::isfinite(readout_s))) return fail("readout_s must be >= 0");
  if (exposure_s + readout_s > frame_period_s() + 1e-12)
    return fail("exposure_s + readout_s must not exceed the frame period 1 / rate_hz");
  if (!finite_positive(quantum_rate_e_per_s)) return fail("quantum_rate_e_per_s must be > 0");
  if (!finite_positive(full_well_e)) return fail("full_well_e must be > 0");
  if (!(read_noise_e >= 0.0 && std::isfinite(read_noise_e))) return fail("read_noise_e must be >= 0");
  if (!finite_positive(gain)) return fail("gain must be > 0");
  if (!(gamma >= 0.1 && gamma <= 10.0)) return fail("gamma must be in [0.1, 10]");
  if (blur_subframes < 2 || blur_subframes > 64) return fail("blur_subframes must be in [2, 64]");
  if (threads < 1 || threads > 64) return fail("threads must be in [1, 64]");
  if (!finite_positive(max_range_m)) return fail("max_range_m must be > 0");
  return true;
}

Eigen::Vector2d DistortNormalized(const rotolidar::CameraIntrinsics& k, const Eigen::Vector2d& xy) {
  return Distort(k, xy, nullptr);
}

Eigen::Vector2d ProjectToPixel(const rotolidar::CameraIntrinsics& k, const Eigen::Vector3d& p_cam) {
  const Eigen::Vector2d d = Distort(k, Eigen::Vector2d(p_cam.x() / p_cam.z(), p_cam.y() / p_cam.z()), nullptr);
  return Eigen::Vector2d(k.fx_px * d.x() + k.cx_px, k.fy_px * d.y() + k.cy_px);
}

bool UndistortPixel(const rotolidar::CameraIntrinsics& k, const Eigen::Vector2d& uv_px, Eigen::Vector2d* xy) {
  const Eigen::Vector2d target((uv_px.x() - k.cx_px) / k.fx_px, (uv_px.y() - k.cy_px) / k.fy_px);
  Eigen::Vector2d p = target;  // the pinhole guess
  for (int i = 0; i < 50; ++i) {
    Eigen::Matrix2d J;
    const Eigen::Vector2d residual = Distort(k, p, &J) - target;
    if (residual.norm() < 1e-12) {
      *xy = p;
      return true;
    }
    if (std::abs(J.determinant()) < 1e-9) return false;
    p -= J.inverse() * residual;
    if (!p.allFinite() || p.norm() > 100.0) return false;
  }
  return false;
}

PixelRayTable MakePixelRayTable(const rotolidar::CameraIntrinsics& k) {
  PixelRayTable table;
  table.width = k.width_px;
  table.height = k.height_px;
  table.xy.resize(static_cast<std::size_t>(k.width_px) * static_cast<std::size_t>(k.height_px));
  for (int v = 0; v < k.height_px; ++v) {
    for (int u = 0; u < k.width_px; ++u) {
      Eigen::Vector2d xy;
      ROTOLIDAR_CHECK(UndistortPixel(k, Eigen::Vector2d(u, v), &xy), "lens not invertible at pixel " << u << "," << v);
      table.xy[static_cast<std::size_t>(v * k.width_px + u)] = xy.cast<float>();
    }
  }
  return table;
}

}  // namespace rotolidar::sim
