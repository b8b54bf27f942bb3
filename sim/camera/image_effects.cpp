// Motion blur and the image sensor (contracts in image_effects.hpp).
#include "sim/camera/image_effects.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

#include "core/util/log.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::sim {
namespace {

uint64_t Mix64(uint64_t x) {  // SplitMix64's finaliser
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// Inverse of the standard normal CDF (Acklam's rational approximation, relative error < 1.2e-9).
double InverseNormalCdf(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01,  -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  const double lo = 0.02425;
  if (p < lo || p > 1.0 - lo) {
    const double q = std::sqrt(-2.0 * std::log(p < lo ? p : 1.0 - p));
    const double x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
                     ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    return p < lo ? x : -x;
  }
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
}

/// N(0, 1) at the centres of 65,536 equal-probability bins: one 16-bit uniform draw -> one normal draw.
const std::vector<float>& NormalTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(65536);
    for (int i = 0; i < 65536; ++i) t[static_cast<std::size_t>(i)] = static_cast<float>(InverseNormalCdf((i + 0.5) / 65536.0));
    return t;
  }();
  return table;
}

/// Bilinear sample of an RGB float image at (x, y) [px], clamped to the border.
void Bilinear(const RadianceImage& im, float x, float y, float* out) {
  x = std::clamp(x, 0.0f, static_cast<float>(im.width - 1));
  y = std::clamp(y, 0.0f, static_cast<float>(im.height - 1));
  const int x0 = std::min(static_cast<int>(x), im.width - 2 < 0 ? 0 : im.width - 2);
  const int y0 = std::min(static_cast<int>(y), im.height - 2 < 0 ? 0 : im.height - 2);
  const float fx = x - x0, fy = y - y0;
  const float* p00 = &im.rgb[3 * (static_cast<std::size_t>(y0) * im.width + x0)];
  const float* p01 = p00 + 3;
  const float* p10 = p00 + 3 * static_cast<std::size_t>(im.width);
  const float* p11 = p10 + 3;
  for (int c = 0; c < 3; ++c) {
    const float top = p00[c] + fx * (p01[c] - p00[c]);
    const float bottom = p10[c] + fx * (p11[c] - p10[c]);
    out[c] = top + fy * (bottom - top);
  }
}

}  // namespace

void RadianceImage::Resize(int w, int h) {
  width = w;
  height = h;
  rgb.assign(static_cast<std::size_t>(3 * w) * static_cast<std::size_t>(h), 0.0f);
  depth_m.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0.0f);
}

void ParallelRows(int rows, int threads, int block_rows, const std::function<void(int, int)>& fn) {
  block_rows = std::max(1, block_rows);
  const int blocks = (rows + block_rows - 1) / block_rows;
  std::atomic<int> next{0};
  const auto work = [&] {
    for (int b = next++; b < blocks; b = next++) fn(b * block_rows, std::min(rows, (b + 1) * block_rows));
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < std::min(threads, blocks); ++i) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

double ApplyVelocityBlur(const rotolidar::CameraIntrinsics& k, const PixelRayTable& rays, const ExposureMotion& motion,
                         const RadianceImage& sharp, int threads, RadianceImage* blurred) {
  ROTOLIDAR_CHECK(rays.width == sharp.width && rays.height == sharp.height, "ray table and image sizes differ");
  blurred->width = sharp.width;
  blurred->height = sharp.height;
  blurred->rgb.resize(sharp.rgb.size());
  blurred->depth_m = sharp.depth_m;
  std::vector<double> row_max(static_cast<std::size_t>(sharp.height), 0.0);
  const Eigen::Matrix3d R_s = motion.T_mid_start.linear(), R_e = motion.T_mid_end.linear();
  const Eigen::Vector3d t_s = motion.T_mid_start.translation(), t_e = motion.T_mid_end.translation();
  ParallelRows(sharp.height, threads, 8, [&](int v0, int v1) {
    for (int v = v0; v < v1; ++v) {
      for (int u = 0; u < sharp.width; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * sharp.width + u;
        const Eigen::Vector2f& xy = rays.xy[i];
        const Eigen::Vector3d ray(xy.x(), xy.y(), 1.0);
        const double z = sharp.depth_m[i];
        // Where the point this pixel sees at the exposure's start / end lies in the mid-exposure image.
        const Eigen::Vector3d p_s = z > 0.0 ? Eigen::Vector3d(R_s * (ray * z) + t_s) : Eigen::Vector3d(R_s * ray);
        const Eigen::Vector3d p_e = z > 0.0 ? Eigen::Vector3d(R_e * (ray * z) + t_e) : Eigen::Vector3d(R_e * ray);
        const Eigen::Vector2d x(u, v);
        const Eigen::Vector2d y_s = p_s.z() > 1e-6 ? ProjectToPixel(k, p_s) : x;
        const Eigen::Vector2d y_e = p_e.z() > 1e-6 ? ProjectToPixel(k, p_e) : x;
        const double half = std::min(64.0, std::max((y_s - x).norm(), (y_e - x).norm()));
        row_max[static_cast<std::size_t>(v)] = std::max(row_max[static_cast<std::size_t>(v)], half);
        float* out = &blurred->rgb[3 * i];
        if (half < 0.05) {
          std::copy_n(&sharp.rgb[3 * i], 3, out);
          continue;
        }
        const int taps = std::min(33, 1 + static_cast<int>(std::ceil(4.0 * half)));
        float sum[3] = {0, 0, 0}, tap[3];
        for (int j = 0; j < taps; ++j) {
          const double tau = -0.5 + (j + 0.5) / taps;  // in exposures, 0 = mid-exposure
          const Eigen::Vector2d y = tau < 0 ? Eigen::Vector2d(x + (-2.0 * tau) * (y_s - x))
                                            : Eigen::Vector2d(x + (2.0 * tau) * (y_e - x));
          Bilinear(sharp, static_cast<float>(y.x()), static_cast<float>(y.y()), tap);
          for (int c = 0; c < 3; ++c) sum[c] += tap[c];
        }
        for (int c = 0; c < 3; ++c) out[c] = sum[c] / static_cast<float>(taps);
      }
    }
  });
  return *std::max_element(row_max.begin(), row_max.end());
}

uint64_t FrameNoiseSeed(uint64_t run_seed, long frame_index) {
  return Mix64(StreamSeed(run_seed, "camera.noise") ^ Mix64(static_cast<uint64_t>(frame_index)));
}

void ExposeSensor(const CameraConfig& config, const RadianceImage& radiance, uint64_t noise_seed, int threads,
                  cv::Mat* bgr8) {
  const std::vector<float>& normal = NormalTable();
  const float e_per_radiance = static_cast<float>(config.quantum_rate_e_per_s * config.exposure_s);
  const float full_well = static_cast<float>(config.full_well_e);
  const float read_var = static_cast<float>(config.read_noise_e * config.read_noise_e);
  const float dn_per_e = static_cast<float>(config.gain * 255.0 / config.full_well_e);
  // Gamma on a 4,096-step table over [0, 255] DN, linearly interpolated (identity when gamma = 1).
  std::vector<float> gamma_lut;
  if (config.gamma != 1.0) {
    gamma_lut.resize(4098);
    for (int i = 0; i < 4098; ++i)
      gamma_lut[static_cast<std::size_t>(i)] =
          static_cast<float>(255.0 * std::pow(std::min(1.0, i / 4096.0), 1.0 / config.gamma));
  }
  bgr8->create(radiance.height, radiance.width, CV_8UC3);
  ParallelRows(radiance.height, threads, 8, [&](int v0, int v1) {
    for (int v = v0; v < v1; ++v) {
      RandomStream rng(Mix64(noise_seed ^ Mix64(static_cast<uint64_t>(v) + 0x5bd1e995ULL)));
      uint64_t bits = 0;
      int left = 0;
      uint8_t* out = bgr8->ptr<uint8_t>(v);
      const float* in = &radiance.rgb[3 * static_cast<std::size_t>(v) * radiance.width];
      for (int i = 0; i < 3 * radiance.width; ++i) {
        if (left == 0) bits = rng.NextU64(), left = 4;
        const float n = normal[bits & 0xffff];
        bits >>= 16;
        --left;
        const float e = std::max(in[i], 0.0f) * e_per_radiance;  // a full well reads full: clip after the noise
        const float measured = std::clamp(e + std::sqrt(std::min(e, full_well) + read_var) * n, 0.0f, full_well);
        float dn = std::min(measured * dn_per_e, 255.0f);
        if (!gamma_lut.empty()) {
          const float x = dn * (4096.0f / 255.0f);
          const int j = static_cast<int>(x);
          dn = gamma_lut[static_cast<std::size_t>(j)] +
               (x - j) * (gamma_lut[static_cast<std::size_t>(j) + 1] - gamma_lut[static_cast<std::size_t>(j)]);
        }
        out[3 * (i / 3) + 2 - i % 3] = static_cast<uint8_t>(dn + 0.5f);  // RGB in, BGR out
      }
    }
  });
}

}  // namespace rotolidar::sim
