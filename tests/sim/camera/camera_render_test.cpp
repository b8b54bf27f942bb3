// The camera twin on real scenes: OpenCV finds ORB features on the lab's textured walls, KLT tracks agree with
// the true motion, the garage's low light lowers image quality, frames are byte-identical for a seed, dynamic
// objects appear where they are at the frame time, and the two renderers see the same geometry.
// Set ROTOLIDAR_CAMERA_TEST_DUMP=DIR to write the test images there (for looking at them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <memory>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "sim/camera/camera_stream.hpp"
#include "sim/sim_config.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/offscreen_render.hpp"
#include "sim/world/scene.hpp"
#include "sim/world/scene_dynamic.hpp"

namespace rotolidar::sim {
namespace {

void Dump(const std::string& name, const cv::Mat& image) {
  if (const char* dir = std::getenv("ROTOLIDAR_CAMERA_TEST_DUMP")) cv::imwrite(std::string(dir) + "/" + name, image);
}

/// A loaded scene with its Embree scene and a camera simulator on it.
struct Rig {
  Scene scene;
  std::unique_ptr<EmbreeScene> embree;
  std::unique_ptr<CameraSimulator> camera;
};

void MakeRig(const std::string& scene_name, const CameraConfig& config, Rig* rig, uint64_t seed = 1,
             const SceneLighting* lighting = nullptr) {
  Status s = LoadScene(ResolveScenePath(scene_name), &rig->scene);
  ASSERT_TRUE(s.ok) << s.message;
  if (lighting) rig->scene.lighting = *lighting;
  s = EmbreeScene::Create(rig->scene, &rig->embree);
  ASSERT_TRUE(s.ok) << s.message;
  s = CameraSimulator::Create(config, seed, rig->scene, rig->embree.get(), &rig->camera);
  ASSERT_TRUE(s.ok) << s.message;
}

cv::Mat Render(Rig& rig, long index, Seconds t, const CameraPoseFn& pose) {
  cv::Mat image;
  const Status s = rig.camera->RenderFrame(index, t, pose, &image);
  EXPECT_TRUE(s.ok) << s.message;
  return image;
}

cv::Mat Grey(const cv::Mat& bgr) {
  cv::Mat g;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  return g;
}

/// ORB as ORB-SLAM runs it on low-contrast cells: 2000 features, FAST threshold 7 (its fallback; OpenCV's
/// default 20 finds almost nothing but outlines on the scenes' subtle plaster and concrete at indoor light).
cv::Ptr<cv::ORB> Orb() { return cv::ORB::create(2000, 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 7); }

int OrbCount(const cv::Mat& bgr) {
  std::vector<cv::KeyPoint> keypoints;
  Orb()->detect(Grey(bgr), keypoints);
  return static_cast<int>(keypoints.size());
}

/// Mean grey level over the temporal noise's sigma, from two frames of the same view with independent noise.
double Snr(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat ga, gb, diff;
  Grey(a).convertTo(ga, CV_32F);
  Grey(b).convertTo(gb, CV_32F);
  cv::subtract(ga, gb, diff);
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff, mean, stddev);
  return cv::mean(ga)[0] / (stddev[0] / std::sqrt(2.0));
}

// Room A of the lab, looking west-north-west past the desks at the poster, bookshelf, window and walls.
const Pose3 kLabView = LookAt(Eigen::Vector3d(6.6, 1.4, 1.45), Eigen::Vector3d(0.0, 4.2, 1.2));

/// The surface the ray through pixel uv of the camera at T hits: world point *X and the hit; false for no hit.
bool SurfaceAt(const EmbreeScene& embree, const rotolidar::CameraIntrinsics& k, const Pose3& T,
               const Eigen::Vector2d& uv, Eigen::Vector3d* X, RayHit* hit) {
  Eigen::Vector2d xy;
  if (!UndistortPixel(k, uv, &xy)) return false;
  const Eigen::Vector3d dir = T.linear() * Eigen::Vector3d(xy.x(), xy.y(), 1.0);
  *hit = embree.Intersect(T.translation(), dir, 100.0);
  if (!hit->hit) return false;
  *X = T.translation() + hit->distance_m * dir.normalized();
  return true;
}

/// True when pixel uv sees the inside of one surface: the rays 4 px away in 4 directions hit the same material
/// on the same plane (no depth edge, no junction of two surfaces such as a wall meeting the floor).
bool InsideOneSurface(const EmbreeScene& embree, const rotolidar::CameraIntrinsics& k, const Pose3& T,
                      const Eigen::Vector2d& uv, Eigen::Vector3d* X, RayHit* hit) {
  if (!SurfaceAt(embree, k, T, uv, X, hit)) return false;
  for (const Eigen::Vector2d& d :
       {Eigen::Vector2d(4, 0), Eigen::Vector2d(-4, 0), Eigen::Vector2d(0, 4), Eigen::Vector2d(0, -4)}) {
    Eigen::Vector3d Y;
    RayHit other;
    if (!SurfaceAt(embree, k, T, uv + d, &Y, &other) || other.material_id != hit->material_id ||
        other.normal_world.dot(hit->normal_world) < 0.999 || std::abs(hit->normal_world.dot(Y - *X)) > 0.005)
      return false;
  }
  return true;
}

/// ORB keypoints of the image that lie inside one surface (not on its outline).
int OrbInsideSurfaces(const cv::Mat& bgr, const EmbreeScene& embree, const rotolidar::CameraIntrinsics& k,
                      const Pose3& T) {
  std::vector<cv::KeyPoint> keypoints;
  Orb()->detect(Grey(bgr), keypoints);
  int inside = 0;
  for (const cv::KeyPoint& kp : keypoints) {
    Eigen::Vector3d X;
    RayHit hit;
    inside += InsideOneSurface(embree, k, T, Eigen::Vector2d(kp.pt.x, kp.pt.y), &X, &hit);
  }
  return inside;
}

/// The default camera on the given renderer.
CameraConfig On(CameraRendererKind kind) {
  CameraConfig c;
  c.renderer = kind;
  return c;
}

CameraPoseFn Static(const Pose3& T) {
  return [T](Seconds) { return T; };
}

TEST(CameraRender, OrbFindsFeaturesOnTheLabsTexturedWalls) {
  Rig rig;
  MakeRig("lab", On(CameraRendererKind::kEmbree), &rig);
  const cv::Mat image = Render(rig, 0, 0.0, Static(kLabView));
  Dump("lab.png", image);
  const int orb = OrbCount(image);
  const int inside = OrbInsideSurfaces(image, *rig.embree, rig.camera->config().Intrinsics(), kLabView);
  std::cout << "ORB keypoints: " << orb << ", inside surfaces " << inside << "\n";
  // Measured 1,594 keypoints, 539 of them inside a surface (texture, not outlines). Bounds at ~2/3 of that.
  EXPECT_GT(orb, 1000);
  EXPECT_GT(inside, 350);
  // Nearly every pixel sees a surface (a closed room): depth > 0 and within the room's 16 m diagonal.
  const RadianceImage& r = rig.camera->last_radiance();
  const long seen = std::count_if(r.depth_m.begin(), r.depth_m.end(), [](float z) { return z > 0.2f && z < 17.f; });
  EXPECT_EQ(seen, static_cast<long>(r.depth_m.size()));
}

TEST(CameraRender, SameSeedSameBytesAnyThreadCount) {
  CameraConfig one = On(CameraRendererKind::kEmbree);
  one.threads = 1;
  CameraConfig two = On(CameraRendererKind::kEmbree);
  two.threads = 3;
  Rig a, b, c;
  MakeRig("lab", one, &a, 5);
  MakeRig("lab", two, &b, 5);
  MakeRig("lab", two, &c, 6);
  // A moving camera so that the velocity blur runs too.
  const CameraPoseFn pose = [](Seconds t) {
    Pose3 T = kLabView;
    T.translation() += Eigen::Vector3d(0.8, 0.3, 0.0) * t;
    return T;
  };
  const cv::Mat ia = Render(a, 7, 0.25, pose), ib = Render(b, 7, 0.25, pose), ic = Render(c, 7, 0.25, pose);
  EXPECT_EQ(cv::norm(ia, ib, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(ia, ic, cv::NORM_L1), 0.0);  // another seed: other noise
}

/// The same view with every texture removed: the features inside surfaces come from the textures.
TEST(CameraRender, TexturesCarryTheFeatures) {
  Rig textured, plain;
  MakeRig("lab", On(CameraRendererKind::kEmbree), &textured);
  ASSERT_NO_FATAL_FAILURE(MakeRig("lab", On(CameraRendererKind::kEmbree), &plain));
  Scene untextured = plain.scene;
  for (Material& m : untextured.materials) m.texture.clear();
  std::unique_ptr<EmbreeScene> embree;
  ASSERT_TRUE(EmbreeScene::Create(untextured, &embree).ok);
  std::unique_ptr<CameraSimulator> camera;
  ASSERT_TRUE(CameraSimulator::Create(On(CameraRendererKind::kEmbree), 1, untextured, embree.get(), &camera).ok);
  cv::Mat flat;
  ASSERT_TRUE(camera->RenderFrame(0, 0.0, Static(kLabView), &flat).ok);
  Dump("lab_untextured.png", flat);
  const rotolidar::CameraIntrinsics k = CameraConfig{}.Intrinsics();
  const int with = OrbInsideSurfaces(Render(textured, 0, 0.0, Static(kLabView)), *textured.embree, k, kLabView);
  const int without = OrbInsideSurfaces(flat, *embree, k, kLabView);
  std::cout << "ORB keypoints inside surfaces: textured " << with << ", untextured " << without << "\n";
  // Untextured surfaces are flat: keypoints remain only on outlines (measured 539 vs 11 inside). Bound: 4x.
  EXPECT_GT(with, 4 * without);
}

/// Two frames 1/30 s apart along a constant-velocity motion (walking pace plus a turn). For each KLT track:
/// the truth point (the ray through the track's first position, at the Embree hit's depth) must reproject onto
/// that position, and its projection into the second frame must match where KLT found it.
class KltTest : public ::testing::TestWithParam<CameraRendererKind> {};

TEST_P(KltTest, TracksAgreeWithTheTrueMotion) {
  Rig rig;
  MakeRig("lab", On(GetParam()), &rig);
  const Eigen::Vector3d v_world(-0.6, 0.5, 0.05);  // [m/s]
  const double yaw_rate = 0.35;                     // [rad/s], 20 deg/s
  const CameraPoseFn pose = [&](Seconds t) {
    Pose3 T = kLabView;
    T.linear() = Eigen::AngleAxisd(yaw_rate * t, Eigen::Vector3d::UnitZ()).toRotationMatrix() * T.linear();
    T.translation() += v_world * t;
    return T;
  };
  const double t1 = 0.5 / 30.0, t2 = 1.5 / 30.0;
  const cv::Mat g1 = Grey(Render(rig, 0, t1, pose)), g2 = Grey(Render(rig, 1, t2, pose));
  Dump("klt_1.png", g1);
  Dump("klt_2.png", g2);
  std::vector<cv::Point2f> p1, p2;
  cv::goodFeaturesToTrack(g1, p1, 2000, 0.002, 5);
  ASSERT_GT(p1.size(), 150u);
  std::vector<uchar> status;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(g1, g2, p1, p2, status, err, cv::Size(21, 21), 3);
  const rotolidar::CameraIntrinsics k = rig.camera->config().Intrinsics();
  const Pose3 T1 = pose(t1), T2 = pose(t2);
  std::vector<double> errors, klt_shift, truth_shift;
  double worst_self = 0.0;
  for (std::size_t i = 0; i < p1.size(); ++i) {
    if (!status[i]) continue;
    const Eigen::Vector2d a(p1[i].x, p1[i].y), b(p2[i].x, p2[i].y);
    // Only corners inside one surface: at a depth edge or a junction of two surfaces (wall/floor) the two sides
    // move differently or the corner slides along a straight boundary (the aperture problem), and KLT follows
    // neither.
    Eigen::Vector3d X;
    RayHit surface;
    if (!InsideOneSurface(*rig.embree, k, T1, a, &X, &surface)) continue;
    // Visible from the second pose (not occluded by something nearer).
    const Eigen::Vector3d to_X = X - T2.translation();
    const RayHit seen = rig.embree->Intersect(T2.translation(), to_X, 100.0);
    if (!seen.hit || seen.distance_m < to_X.norm() - 0.01) continue;
    worst_self = std::max(worst_self, (ProjectToPixel(k, T1.inverse() * X) - a).norm());
    const Eigen::Vector2d truth = ProjectToPixel(k, T2.inverse() * X);
    errors.push_back((truth - b).norm());
    klt_shift.push_back((b - a).norm());
    truth_shift.push_back((truth - a).norm());
  }
  ASSERT_GT(errors.size(), 300u) << "tracks inside surfaces";
  const auto quantile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * (v.size() - 1))];
  };
  // Truth points reproject onto their own pixel: the lens model and the Embree hit agree (float rays: < 1e-3 px).
  EXPECT_LT(worst_self, 1e-3);
  // KLT against the truth. Measured (seed 1), embree: median 0.17 px, 90 % within 0.71 px over ~1,000 tracks
  // (without noise and blur: 0.07 / 0.52 px; the rest is KLT on low-contrast, magnified textures); shift medians
  // 0.06 px apart. osmesa: 0.46 / 1.68 px over ~650 tracks, shifts 0.14 px apart (a pinhole render resampled
  // by cv::remap, per-vertex lighting and OpenGL's mip-mapping). Bounds with margin per renderer.
  const bool embree = GetParam() == CameraRendererKind::kEmbree;
  const double median = quantile(errors, 0.5), p90 = quantile(errors, 0.9);
  EXPECT_LT(median, embree ? 0.3 : 0.7);
  EXPECT_LT(p90, embree ? 1.0 : 2.5);
  const double klt_median = quantile(klt_shift, 0.5), truth_median = quantile(truth_shift, 0.5);
  EXPECT_GT(truth_median, 3.0);  // ~5 px of image motion per frame
  EXPECT_NEAR(klt_median, truth_median, embree ? 0.15 : 0.3);
  std::cout << CameraRendererName(GetParam()) << ": KLT vs truth over " << errors.size() << " tracks: median " << median << " px, 90 % " << p90
            << " px; median shift KLT " << klt_median << " px, truth " << truth_median << " px\n";
}

INSTANTIATE_TEST_SUITE_P(CameraRender, KltTest,
                         ::testing::Values(CameraRendererKind::kEmbree, CameraRendererKind::kOsmesa),
                         [](const auto& info) { return std::string(CameraRendererName(info.param)); });

// The garage's light (ambient 0.06, weak lights) against the lab's, on the same lab view and on the garage itself.
TEST(CameraRender, GarageLowLightLowersImageQuality) {
  Scene garage;
  ASSERT_TRUE(LoadScene(ResolveScenePath("garage"), &garage).ok);
  Rig lab, dim, garage_rig;
  MakeRig("lab", On(CameraRendererKind::kEmbree), &lab);
  MakeRig("lab", On(CameraRendererKind::kEmbree), &dim, 1, &garage.lighting);
  MakeRig("garage", On(CameraRendererKind::kEmbree), &garage_rig);
  const Pose3 garage_view = LookAt(Eigen::Vector3d(4.0, 5.0, 1.5), Eigen::Vector3d(30.0, 18.0, 1.0));
  const cv::Mat lab_a = Render(lab, 0, 0.0, Static(kLabView)), lab_b = Render(lab, 1, 0.0, Static(kLabView));
  const cv::Mat dim_a = Render(dim, 0, 0.0, Static(kLabView)), dim_b = Render(dim, 1, 0.0, Static(kLabView));
  const cv::Mat gar_a = Render(garage_rig, 0, 0.0, Static(garage_view));
  const cv::Mat gar_b = Render(garage_rig, 1, 0.0, Static(garage_view));
  Dump("lab_garage_light.png", dim_a);
  Dump("garage.png", gar_a);
  const double lab_mean = cv::mean(Grey(lab_a))[0], dim_mean = cv::mean(Grey(dim_a))[0];
  const double gar_mean = cv::mean(Grey(gar_a))[0];
  const double lab_snr = Snr(lab_a, lab_b), dim_snr = Snr(dim_a, dim_b), gar_snr = Snr(gar_a, gar_b);
  const int lab_orb = OrbCount(lab_a), dim_orb = OrbCount(dim_a), gar_orb = OrbCount(gar_a);
  std::cout << "mean grey / SNR / ORB: lab " << lab_mean << " / " << lab_snr << " / " << lab_orb
            << "; lab view in garage light " << dim_mean << " / " << dim_snr << " / " << dim_orb << "; garage "
            << gar_mean << " / " << gar_snr << " / " << gar_orb << "\n";
  // Shot noise: SNR grows as sqrt(signal), so ~4x less light gives ~half the SNR. Measured mean grey / SNR /
  // ORB: lab 77 / 61 / 1594, lab view in garage light 17 / 26 / 293, garage 11 / 19 / 612. Bounds with margin.
  EXPECT_LT(dim_mean, 0.5 * lab_mean);
  EXPECT_LT(dim_snr, 0.75 * lab_snr);
  EXPECT_LT(dim_orb, lab_orb);
  EXPECT_LT(gar_mean, 0.5 * lab_mean);
  EXPECT_LT(gar_snr, 0.75 * lab_snr);
  EXPECT_LT(gar_orb, lab_orb);
}

/// The garage's walker crosses the line of sight: the centre pixel sees it when the scene's motion model puts it
/// there, and the far wall otherwise, with both renderers.
TEST(CameraRender, DynamicObjectsAppearAtTheirPoseAtTheFrameTime) {
  Scene scene;
  ASSERT_TRUE(LoadScene(ResolveScenePath("garage"), &scene).ok);
  std::size_t walker = 0;
  while (walker < scene.dynamic_objects.size() && scene.dynamic_objects[walker].name != "walker_cross") ++walker;
  ASSERT_LT(walker, scene.dynamic_objects.size());
  const DynamicObject& object = scene.dynamic_objects[walker];
  const Seconds t_cross = 3.2 / 1.2;  // (20, 16.8) -> y = 20 at 1.2 m/s
  ASSERT_NEAR(DynamicObjectPose(object, t_cross).translation().y(), 20.0, 1e-9);
  const Pose3 view = LookAt(Eigen::Vector3d(12.0, 20.0, 1.2), Eigen::Vector3d(20.0, 20.0, 1.2));
  for (const CameraRendererKind kind : {CameraRendererKind::kEmbree, CameraRendererKind::kOsmesa}) {
    CameraConfig c;
    c.renderer = kind;
    c.motion_blur = MotionBlurKind::kNone;
    Rig rig;
    MakeRig("garage", c, &rig);
    const std::size_t centre = static_cast<std::size_t>(240 * 640 + 320);
    Render(rig, 0, t_cross, Static(view));
    const float z_person = rig.camera->last_radiance().depth_m[centre];
    Render(rig, 1, 0.0, Static(view));
    const float z_empty = rig.camera->last_radiance().depth_m[centre];
    // The person's torso is 0.2..0.3 m deep around its path point 8 m ahead; the far wall is 52 m away.
    EXPECT_NEAR(z_person, 7.88, 0.15) << CameraRendererName(kind);
    EXPECT_NEAR(z_empty, 52.0, 0.5) << CameraRendererName(kind);
  }
}

/// Both renderers see the same geometry through the same lens: depth agrees almost everywhere (differences at
/// silhouettes, where one pixel's nearest sample lands on the other side), and the brightness is similar
/// (OpenGL's per-vertex lighting and specular differ from the ray caster's per-pixel Lambert).
TEST(CameraRender, OsmesaAndEmbreeRenderTheSameScene) {
  CameraConfig ce = On(CameraRendererKind::kEmbree), co = On(CameraRendererKind::kOsmesa);
  ce.motion_blur = co.motion_blur = MotionBlurKind::kNone;
  Rig e, o;
  MakeRig("lab", ce, &e);
  MakeRig("lab", co, &o);
  const cv::Mat ie = Render(e, 0, 0.0, Static(kLabView)), io = Render(o, 0, 0.0, Static(kLabView));
  Dump("lab_osmesa.png", io);
  const std::vector<float>& ze = e.camera->last_radiance().depth_m;
  const std::vector<float>& zo = o.camera->last_radiance().depth_m;
  long agree = 0;
  for (std::size_t i = 0; i < ze.size(); ++i) agree += std::abs(ze[i] - zo[i]) < 0.01f * ze[i] + 0.005f;
  const double fraction = static_cast<double>(agree) / static_cast<double>(ze.size());
  const double mean_e = cv::mean(Grey(ie))[0], mean_o = cv::mean(Grey(io))[0];
  std::cout << "depth agrees (1 %) on " << 100.0 * fraction << " % of pixels; mean grey embree " << mean_e
            << ", osmesa " << mean_o << "; ORB " << OrbCount(ie) << " vs " << OrbCount(io) << "\n";
  EXPECT_GT(fraction, 0.97);  // measured ~99 %: only silhouette pixels differ
  EXPECT_NEAR(mean_o / mean_e, 1.0, 0.25);
}

}  // namespace
}  // namespace rotolidar::sim
