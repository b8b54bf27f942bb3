#pragma once
// The camera rendered by MuJoCo's OpenGL renderer through OSMesa (software rasterisation; sim/world/
// offscreen_render.hpp), from the MuJoCo model of the same scene (sim/world/scene_mujoco.hpp), then distorted
// with cv::remap (docs/camera_model.md).
//
// A pinhole image (square pixels, f = max(fx, fy)) large enough to hold the whole undistorted field of view is
// rendered without multisampling or shadows; each output pixel then samples it (bilinear; depth: nearest) at the
// pinhole position of its own undistorted ray (PixelRayTable), so both renderers see through the same lens.
// Lighting is OpenGL's (per-vertex, MuJoCo's headlight, ambient and lights, a little specular), textures
// MuJoCo's (texuniform planes); pixels that see nothing show MuJoCo's sky gradient. Rolling shutter is not
// modelled here: every row uses the middle row's pose. Never link libEGL into a process that uses this.
#include <memory>
#include <vector>

#include "sim/camera/camera_model.hpp"
#include "sim/camera/camera_renderer.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {

class OsmesaCameraRenderer : public CameraRenderer {
 public:
  /// Compiles the scene into MuJoCo and opens an OSMesa context. Fails with MuJoCo's or OSMesa's message.
  static Status Create(const Scene& scene, const CameraConfig& config, std::unique_ptr<OsmesaCameraRenderer>* out);
  ~OsmesaCameraRenderer() override;

  Status Render(Seconds t_s, const std::vector<Pose3>& T_world_cam_rows, RadianceImage* out) override;
  const char* name() const override { return "osmesa"; }
  const PixelRayTable& rays() const { return rays_; }

 private:
  struct Impl;
  OsmesaCameraRenderer() = default;
  PixelRayTable rays_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rotolidar::sim
