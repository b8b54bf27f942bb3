#pragma once
// The camera rendered by ray casting against the same Embree scene as the LiDAR (docs/camera_model.md).
//
// One ray per pixel centre through the lens model (PixelRayTable, distortion included, so no resampling), cast
// row by row through EmbreeScene::IntersectBatch (Embree's coherent stream API, rtcIntersect1M), rows spread
// over `threads` threads. Shading: the hit material's albedo (its texture, mip-mapped by the pixel's footprint,
// times its colour) under the scene's light (SceneLighting): ambient + the headlight (a directional light along
// the camera's optical axis, as MuJoCo's) + each light (directional, or a spot light with MuJoCo's defaults:
// 45 deg cutoff, exponent 10, no attenuation); lights with cast_shadow cast shadows (one shadow ray per lit pixel)
// when config.shadows. Lambert only (no specular). Rays that hit nothing within max_range_m see the sky colour.
//
// Texture placement: every triangle gets a texture frame from its normal and its primitive (origin at the
// primitive's centre): walls (|n_z| < 0.7) have texture rows along the surface's downhill direction (bricks and
// planks stay level), floors and ceilings the primitive's x axis as texture columns. One texture image covers
// size_m x size_m metres (texture.hpp) and repeats.
//
// Determinism: each row is one ray batch whatever the thread count, so images do not depend on `threads`.
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "sim/camera/camera_model.hpp"
#include "sim/camera/camera_renderer.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {

class EmbreeCameraRenderer : public CameraRenderer {
 public:
  /// `embree` must be built from `scene` (EmbreeScene::Create(scene)) and outlive the renderer; the renderer
  /// calls its SetTime. Fails when the config is invalid or a material's texture is missing.
  static Status Create(const Scene& scene, EmbreeScene* embree, const CameraConfig& config,
                       std::unique_ptr<EmbreeCameraRenderer>* out);
  ~EmbreeCameraRenderer() override;

  Status Render(Seconds t_s, const std::vector<Pose3>& T_world_cam_rows, RadianceImage* out) override;
  const char* name() const override { return "embree"; }
  const PixelRayTable& rays() const { return rays_; }

 private:
  struct Impl;
  EmbreeCameraRenderer() = default;
  PixelRayTable rays_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rotolidar::sim
