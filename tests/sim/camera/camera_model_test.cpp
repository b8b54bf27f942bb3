// The camera's lens model against OpenCV, its configuration and YAML, the sensor's noise statistics and the
// velocity blur against an analytic edge profile.
#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <yaml-cpp/yaml.h>

#include "core/util/rng.hpp"
#include "sim/camera/camera_model.hpp"
#include "sim/camera/image_effects.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::sim {
namespace {

/// A strongly distorted lens (more than the default) so the round trips are not trivially near-pinhole.
CameraConfig StrongLens() {
  CameraConfig c;
  c.k1 = -0.18;
  c.k2 = 0.05;
  c.p1 = 1.5e-3;
  c.p2 = -1.0e-3;
  return c;
}

cv::Mat CameraMatrix(const rotolidar::CameraIntrinsics& k) {
  return (cv::Mat_<double>(3, 3) << k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1);
}

cv::Mat DistCoeffs(const rotolidar::CameraIntrinsics& k) { return (cv::Mat_<double>(1, 4) << k.k1, k.k2, k.p1, k.p2); }

TEST(CameraModel, ProjectionEqualsOpenCvProjectPoints) {
  const rotolidar::CameraIntrinsics k = StrongLens().Intrinsics();
  RandomStream rng(1, "test.camera.project");
  std::vector<cv::Point3d> points;
  for (int i = 0; i < 500; ++i) {  // inside the field of view, 0.3..20 m deep
    const double z = 0.3 + 19.7 * rng.Uniform();
    points.push_back(cv::Point3d{(rng.Uniform() - 0.5) * 1.3 * z, (rng.Uniform() - 0.5) * 1.0 * z, z});
  }
  std::vector<cv::Point2d> expected;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), CameraMatrix(k), DistCoeffs(k), expected);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d uv = ProjectToPixel(k, Eigen::Vector3d(points[i].x, points[i].y, points[i].z));
    // Both evaluate the same polynomial in double: agreement to rounding (1e-9 px is ~1e4 ulps of a pixel value).
    EXPECT_NEAR(uv.x(), expected[i].x, 1e-9);
    EXPECT_NEAR(uv.y(), expected[i].y, 1e-9);
  }
}

TEST(CameraModel, UndistortionRoundTripsAndMatchesOpenCv) {
  const rotolidar::CameraIntrinsics k = StrongLens().Intrinsics();
  std::vector<cv::Point2d> pixels;
  for (int v = 0; v < k.height_px; v += 16)
    for (int u = 0; u < k.width_px; u += 16) pixels.emplace_back(u, v);
  pixels.emplace_back(0, 0);
  pixels.emplace_back(k.width_px - 1, k.height_px - 1);
  std::vector<cv::Point2d> opencv;
  cv::undistortPoints(pixels, opencv, CameraMatrix(k), DistCoeffs(k), cv::noArray(), cv::noArray(),
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-14));
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    Eigen::Vector2d xy;
    ASSERT_TRUE(UndistortPixel(k, Eigen::Vector2d(pixels[i].x, pixels[i].y), &xy));
    // Round trip: Newton converges to 1e-12 in normalised units (~5e-10 px).
    const Eigen::Vector2d back = ProjectToPixel(k, Eigen::Vector3d(xy.x(), xy.y(), 1.0));
    EXPECT_NEAR(back.x(), pixels[i].x, 1e-8);
    EXPECT_NEAR(back.y(), pixels[i].y, 1e-8);
    // OpenCV's fixed-point iteration given 200 iterations converges to the same inverse (1e-9 normalised =
    // 5e-7 px; its iteration contracts slowly in the corners of this strong lens).
    EXPECT_NEAR(xy.x(), opencv[i].x, 1e-9);
    EXPECT_NEAR(xy.y(), opencv[i].y, 1e-9);
  }
}

TEST(CameraModel, PixelRayTableProjectsBackOntoPixelCentres) {
  const rotolidar::CameraIntrinsics k = CameraConfig{}.Intrinsics();
  const PixelRayTable table = MakePixelRayTable(k);
  ASSERT_EQ(table.xy.size(), static_cast<std::size_t>(k.width_px * k.height_px));
  double worst = 0.0;
  for (int v = 0; v < k.height_px; v += 7) {
    for (int u = 0; u < k.width_px; u += 5) {
      const Eigen::Vector2f& xy = table.at(u, v);
      worst = std::max(worst, (ProjectToPixel(k, Eigen::Vector3d(xy.x(), xy.y(), 1.0)) - Eigen::Vector2d(u, v)).norm());
    }
  }
  // Stored as float: |xy| < 0.9 with 2^-24 relative error, times fx = 462 px: < 1e-4 px.
  EXPECT_LT(worst, 1e-4);
}

TEST(CameraConfig, DefaultsAreD435iLike) {
  const CameraConfig c;
  std::string why;
  ASSERT_TRUE(c.Validate(&why)) << why;
  EXPECT_EQ(c.width_px, 640);
  EXPECT_EQ(c.height_px, 480);
  EXPECT_EQ(c.rate_hz, 30.0);
  EXPECT_TRUE(c.enabled);
  const double hfov_deg = 2.0 * std::atan(0.5 * c.width_px / c.fx_px) * 180.0 / M_PI;
  EXPECT_NEAR(hfov_deg, 69.4, 0.1);
  const rotolidar::CameraIntrinsics k = c.Intrinsics();
  EXPECT_EQ(k.fx_px, c.fx_px);
  EXPECT_EQ(k.k1, c.k1);
  EXPECT_EQ(k.rate_hz, 30.0);
}

TEST(CameraConfig, ValidateNamesTheBadField) {
  std::string why;
  CameraConfig c;
  c.k1 = -1.5;  // folds the image back on itself before the corners
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("k1"), std::string::npos) << why;
  c = CameraConfig{};
  c.exposure_s = 0.03;
  c.readout_s = 0.01;  // 40 ms > one 33 ms frame
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("exposure_s + readout_s"), std::string::npos) << why;
  c = CameraConfig{};
  c.width_px = 4;
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("width_px"), std::string::npos) << why;
}

TEST(CameraConfig, SimYamlSectionParsesEmitsAndRejectsUnknownKeys) {
  SimConfig config = DefaultSimConfig();
  const YAML::Node ok = YAML::Load("camera: {enabled: false, rate_hz: 15, width_px: 320, height_px: 240,\n"
                                   "         fx_px: 231, fy_px: 231, cx_px: 160, cy_px: 120, renderer: osmesa,\n"
                                   "         motion_blur: subframes, blur_subframes: 3, exposure_s: 0.02}\n");
  Status s = ParseSimConfig("test.yaml", ok, &config);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_FALSE(config.camera.enabled);
  EXPECT_EQ(config.camera.width_px, 320);
  EXPECT_EQ(config.camera.renderer, CameraRendererKind::kOsmesa);
  EXPECT_EQ(config.camera.motion_blur, MotionBlurKind::kSubframes);
  EXPECT_EQ(config.TrueCalib().camera.fx_px, 231.0);  // calib.yaml carries the configured lens
  EXPECT_EQ(config.TrueCalib().camera.rate_hz, 15.0);
  // Emit -> parse gives the same config.
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  EmitSimConfig(out, config);
  SimConfig again = DefaultSimConfig();
  s = ParseSimConfig("emitted.yaml", YAML::Load(out.c_str()), &again);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(again.camera.enabled, false);
  EXPECT_EQ(again.camera.blur_subframes, 3);
  EXPECT_EQ(again.camera.exposure_s, 0.02);
  EXPECT_EQ(again.camera.k2, config.camera.k2);
  // Unknown keys and bad values are errors naming the file, the line and the key.
  s = ParseSimConfig("bad.yaml", YAML::Load("seed: 2\ncamera:\n  enabled: true\n  exposure: 0.01\n"), &config);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("bad.yaml:"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("exposure"), std::string::npos) << s.message;
  s = ParseSimConfig("bad.yaml", YAML::Load("camera: {renderer: vulkan}\n"), &config);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("camera.renderer"), std::string::npos) << s.message;
}

RadianceImage Flat(int w, int h, float radiance) {
  RadianceImage im;
  im.Resize(w, h);
  std::fill(im.rgb.begin(), im.rgb.end(), radiance);
  return im;
}

TEST(CameraSensor, NoiseMatchesShotPlusReadNoise) {
  const CameraConfig c;
  const float radiance = 0.3f;
  cv::Mat image;
  ExposeSensor(c, Flat(c.width_px, c.height_px, radiance), FrameNoiseSeed(1, 0), 2, &image);
  cv::Scalar mean, stddev;
  cv::meanStdDev(image.reshape(1), mean, stddev);
  const double e = radiance * c.quantum_rate_e_per_s * c.exposure_s;  // 1800 e-
  const double dn_per_e = c.gain * 255.0 / c.full_well_e;
  const double expected_mean = dn_per_e * e;  // 76.5 DN
  const double expected_var = dn_per_e * dn_per_e * (e + c.read_noise_e * c.read_noise_e) + 1.0 / 12.0;  // + rounding
  // 921,600 samples: the mean's standard error is 0.002 DN, the variance's relative one sqrt(2/N) = 0.15 %.
  EXPECT_NEAR(mean[0], expected_mean, 0.02);
  EXPECT_NEAR(stddev[0] * stddev[0], expected_var, 0.02 * expected_var);
  // Saturation: radiance 2 fills the well twice over -> every value 255.
  ExposeSensor(c, Flat(64, 48, 2.0f), FrameNoiseSeed(1, 0), 1, &image);
  EXPECT_EQ(cv::countNonZero(image.reshape(1) != 255), 0);
}

TEST(CameraSensor, SameSeedSameBytesWhateverTheThreads) {
  const CameraConfig c;
  RadianceImage im = Flat(c.width_px, c.height_px, 0.0f);
  RandomStream rng(3, "test.camera.pattern");
  for (float& x : im.rgb) x = static_cast<float>(rng.Uniform());
  cv::Mat one, four, other;
  ExposeSensor(c, im, FrameNoiseSeed(7, 12), 1, &one);
  ExposeSensor(c, im, FrameNoiseSeed(7, 12), 4, &four);
  ExposeSensor(c, im, FrameNoiseSeed(7, 13), 2, &other);
  EXPECT_EQ(cv::norm(one, four, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(one, other, cv::NORM_L1), 0.0);  // another frame, other noise
  EXPECT_NE(FrameNoiseSeed(7, 12), FrameNoiseSeed(8, 12));
}

TEST(CameraBlur, YawSmearsAVerticalEdgeIntoTheExpectedRamp) {
  CameraConfig c;
  c.k1 = c.k2 = c.p1 = c.p2 = 0.0;  // pinhole: the analytic shift is f tan(angle)
  const rotolidar::CameraIntrinsics k = c.Intrinsics();
  const PixelRayTable rays = MakePixelRayTable(k);
  RadianceImage sharp = Flat(c.width_px, c.height_px, 0.0f);
  for (int v = 0; v < c.height_px; ++v)
    for (int u = 320; u < c.width_px; ++u)
      for (int ch = 0; ch < 3; ++ch) sharp.rgb[3 * (v * c.width_px + u) + ch] = 1.0f;
  std::fill(sharp.depth_m.begin(), sharp.depth_m.end(), 3.0f);
  // Yaw about the camera's y axis by -+0.6 deg over the exposure: the scene slides +-f tan(0.6 deg) = 4.84 px.
  const double angle = 0.6 * M_PI / 180.0;
  ExposureMotion motion;
  motion.T_mid_start.linear() = Eigen::AngleAxisd(-angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
  motion.T_mid_end.linear() = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
  RadianceImage blurred;
  const double half_px = ApplyVelocityBlur(k, rays, motion, sharp, 2, &blurred);
  const double s = c.fx_px * std::tan(angle);
  // The largest path: a corner pixel's ray rotated by +-angle, projected (the corners move most).
  double longest = 0.0;
  for (const Eigen::Vector2d& corner : {Eigen::Vector2d(0, 0), Eigen::Vector2d(639, 0), Eigen::Vector2d(0, 479),
                                       Eigen::Vector2d(639, 479)}) {
    Eigen::Vector2d xy;
    ASSERT_TRUE(UndistortPixel(k, corner, &xy));
    for (const Pose3& T : {motion.T_mid_start, motion.T_mid_end})
      longest = std::max(longest, (ProjectToPixel(k, T.linear() * Eigen::Vector3d(xy.x(), xy.y(), 1.0)) - corner).norm());
  }
  EXPECT_GT(longest, s);
  EXPECT_NEAR(half_px, longest, 1e-3);
  // Along the middle row the step becomes a ramp 2 s wide centred on the edge (u = 319.5): value = fraction of the
  // exposure the pixel saw the bright side. Box taps of <= 0.5 px and bilinear sampling: +-0.06.
  const int v = c.height_px / 2;
  for (int u = 312; u <= 327; ++u) {
    const double expected = std::clamp((u - 319.5) / (2.0 * s) + 0.5, 0.0, 1.0);
    EXPECT_NEAR(blurred.rgb[3 * (v * c.width_px + u)], expected, 0.06) << "u = " << u;
  }
  EXPECT_EQ(blurred.rgb[3 * (v * c.width_px + 300)], 0.0f);  // far from the edge: untouched
  EXPECT_EQ(blurred.rgb[3 * (v * c.width_px + 340)], 1.0f);
}

}  // namespace
}  // namespace rotolidar::sim
