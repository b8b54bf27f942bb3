// MuJoCo + OSMesa camera: a pinhole render covering the lens's field of view, remapped through the distortion
// (contract in osmesa_camera.hpp).
#include "sim/camera/osmesa_camera.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "sim/world/offscreen_render.hpp"
#include "sim/world/scene_mujoco.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {

struct OsmesaCameraRenderer::Impl {
  CameraConfig config;
  std::unique_ptr<MujocoScene> mujoco;
  std::unique_ptr<OffscreenRenderer> renderer;
  CameraIntrinsics pinhole;  ///< the render's intrinsics (offscreen_render.hpp's pixel-edge convention)
  RenderSettings settings;
  cv::Mat map_x, map_y;      ///< output pixel -> render pixel (OpenCV's pixel-centre convention)
  RgbImage rgb;
  std::vector<float> depth;
};

OsmesaCameraRenderer::~OsmesaCameraRenderer() = default;

Status OsmesaCameraRenderer::Create(const Scene& scene, const CameraConfig& config,
                                    std::unique_ptr<OsmesaCameraRenderer>* out) {
  ROTOLIDAR_CHECK(out != nullptr, "OsmesaCameraRenderer::Create needs an output");
  std::string why;
  if (!config.Validate(&why)) return Status::Error("osmesa camera: " + why);
  std::unique_ptr<OsmesaCameraRenderer> r(new OsmesaCameraRenderer());
  r->impl_ = std::make_unique<Impl>();
  Impl& m = *r->impl_;
  m.config = config;
  r->rays_ = MakePixelRayTable(config.Intrinsics());
  // The pinhole image that holds every output pixel's ray, with a 2-pixel margin for bilinear sampling.
  Eigen::Vector2f lo = r->rays_.xy.front(), hi = lo;
  for (const Eigen::Vector2f& xy : r->rays_.xy) lo = lo.cwiseMin(xy), hi = hi.cwiseMax(xy);
  const double f = std::max(config.fx_px, config.fy_px);
  const double cx = 2.0 - f * lo.x(), cy = 2.0 - f * lo.y();
  m.pinhole.width_px = static_cast<int>(std::ceil(f * (hi.x() - lo.x()) + 4.0)) + 1;
  m.pinhole.height_px = static_cast<int>(std::ceil(f * (hi.y() - lo.y()) + 4.0)) + 1;
  m.pinhole.fx_px = m.pinhole.fy_px = f;
  m.pinhole.cx_px = cx + 0.5;  // pixel centres at +0.5 in the renderer's edge convention
  m.pinhole.cy_px = cy + 0.5;
  m.map_x.create(config.height_px, config.width_px, CV_32FC1);
  m.map_y.create(config.height_px, config.width_px, CV_32FC1);
  for (int v = 0; v < config.height_px; ++v) {
    for (int u = 0; u < config.width_px; ++u) {
      m.map_x.at<float>(v, u) = static_cast<float>(f * r->rays_.at(u, v).x() + cx);
      m.map_y.at<float>(v, u) = static_cast<float>(f * r->rays_.at(u, v).y() + cy);
    }
  }
  m.settings.far_m = config.max_range_m;
  m.settings.shadows = false;
  if (Status s = MujocoScene::Create(scene, &m.mujoco); !s) return Status::Error("osmesa camera: " + s.message);
  if (Status s = OffscreenRenderer::Create(m.mujoco->model(), m.pinhole.width_px, m.pinhole.height_px, 0, &m.renderer);
      !s)
    return Status::Error("osmesa camera: " + s.message);
  *out = std::move(r);
  return Status::Ok();
}

Status OsmesaCameraRenderer::Render(Seconds t_s, const std::vector<Pose3>& T_world_cam_rows, RadianceImage* out) {
  Impl& m = *impl_;
  const std::size_t h = static_cast<std::size_t>(rays_.height);
  if (T_world_cam_rows.size() != 1 && T_world_cam_rows.size() != h)
    return Status::Error("osmesa camera: need 1 or " + std::to_string(h) + " poses, got " +
                         std::to_string(T_world_cam_rows.size()));
  m.mujoco->SetTime(t_s);
  const Pose3& T_world_cam = T_world_cam_rows[T_world_cam_rows.size() == 1 ? 0 : h / 2];
  if (Status s = m.renderer->Render(m.mujoco->model(), m.mujoco->data(), T_world_cam, m.pinhole, m.settings, &m.rgb,
                                    &m.depth);
      !s)
    return Status::Error("osmesa camera: " + s.message);
  const cv::Mat rgb8(m.rgb.height, m.rgb.width, CV_8UC3, m.rgb.rgb.data());
  const cv::Mat depth(m.rgb.height, m.rgb.width, CV_32FC1, m.depth.data());
  cv::Mat rgb_f;
  rgb8.convertTo(rgb_f, CV_32FC3, 1.0 / 255.0);
  out->Resize(rays_.width, rays_.height);
  cv::Mat out_rgb(rays_.height, rays_.width, CV_32FC3, out->rgb.data());
  cv::Mat out_depth(rays_.height, rays_.width, CV_32FC1, out->depth_m.data());
  cv::remap(rgb_f, out_rgb, m.map_x, m.map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  cv::remap(depth, out_depth, m.map_x, m.map_y, cv::INTER_NEAREST, cv::BORDER_REPLICATE);
  const float far = static_cast<float>(0.999 * m.settings.far_m);
  for (float& z : out->depth_m)
    if (z >= far) z = 0.0f;  // nothing drawn: sky
  return Status::Ok();
}

}  // namespace rotolidar::sim
