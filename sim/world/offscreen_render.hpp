#pragma once
// Offscreen rendering of a MuJoCo model through OSMesa (software OpenGL, no display, no GPU): an RGB image (and
// optionally a depth image) of an mjModel/mjData seen from a given camera pose with pinhole intrinsics. Used by
// `rotolidar scene show` and by the camera simulation.
//
// How: an OSMesa context is made current, then MuJoCo's own rendering context (mjr_makeContext, which uploads
// the model's textures) draws into its offscreen framebuffer; the frustum is set from the intrinsics after
// mjv_updateScene. Never link libEGL into a process that uses this: Debian's MuJoCo 2.2.2 then picks EGL for its
// GL loading and fails without a display. At most 8 lights are drawn (OpenGL's fixed pipeline): the headlight and
// the model's first 7.
//
// Thread safety: one renderer belongs to one thread at a time (Render makes its OSMesa context current on
// the calling thread). Several renderers may live in one process.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>
#include <Eigen/Geometry>

#include "core/util/status.hpp"
#include "sim/world/texture.hpp"

namespace rotolidar::sim {

/// Pinhole intrinsics of the rendered image. MuJoCo's frustum has square pixels: fx must equal fy.
struct CameraIntrinsics {
  int width_px = 640;
  int height_px = 480;
  double fx_px = 500.0;
  double fy_px = 500.0;
  double cx_px = 320.0;  ///< principal point, pixels from the left edge
  double cy_px = 240.0;  ///< pixels from the top edge

  bool Validate(std::string* error) const;
};

struct RenderSettings {
  double near_m = 0.05;   ///< clipping planes along the optical axis [m]
  double far_m = 1000.0;
  bool shadows = false;   ///< shadow maps (slow in software)
  bool skybox = true;     ///< draw the sky (background colour of the scene)
  /// Geom groups drawn (scene_mujoco.hpp: 0 visible, 1 ceilings/roofs, 2 back sides never drawn).
  std::array<bool, 6> geom_groups = {true, true, false, false, false, false};
};

class OffscreenRenderer {
 public:
  /// Creates an OSMesa context and MuJoCo's rendering context for `model` (uploads its textures; sets
  /// model->vis.global.offwidth/offheight to the maxima and offsamples to `multisamples`). Images up to
  /// max_width_px x max_height_px can be rendered. Fails naming what could not be created.
  static Status Create(mjModel* model, int max_width_px, int max_height_px, int multisamples,
                       std::unique_ptr<OffscreenRenderer>* out);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  /// Renders `model` (the one given to Create) in the state `data` (positions must be current, e.g. after
  /// mj_kinematics) from the camera pose T_world_cam (optical frame: z forward, x right, y down).
  /// rgb: width x height, rows top to bottom. depth_m (optional): per pixel, the z distance along the optical
  /// axis [m] (far_m where nothing was drawn). Fails on invalid intrinsics or a size above the maxima.
  Status Render(const mjModel* model, mjData* data, const Eigen::Isometry3d& T_world_cam,
                const CameraIntrinsics& intrinsics, const RenderSettings& settings, RgbImage* rgb,
                std::vector<float>* depth_m = nullptr);

 private:
  OffscreenRenderer() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// T_world_cam of a camera at `eye` looking at `target` with the image's up towards world +z (or +y when
/// looking straight down/up).
Eigen::Isometry3d LookAt(const Eigen::Vector3d& eye_m, const Eigen::Vector3d& target_m);

}  // namespace rotolidar::sim
