// OSMesa context + MuJoCo offscreen framebuffer; the camera frustum comes from pinhole intrinsics.
#include "sim/world/offscreen_render.hpp"
#include "core/util/log.hpp"

#include <GL/osmesa.h>

#include <algorithm>
#include <cmath>

namespace rotolidar::sim {

namespace {

/// The GL camera from the optical frame (z forward, y down: GL forward = z, up = -y) and the frustum at the
/// near plane from the intrinsics (MuJoCo derives left/right from the aspect ratio: square pixels).
void SetGlCamera(const Eigen::Isometry3d& T_world_cam, const CameraIntrinsics& k, const RenderSettings& settings,
                 mjvScene* scn) {
  const Eigen::Matrix3d R = T_world_cam.linear();
  const double n = settings.near_m;
  for (mjvGLCamera& c : scn->camera) {
    for (int i = 0; i < 3; ++i) {
      c.pos[i] = static_cast<float>(T_world_cam.translation()[i]);
      c.forward[i] = static_cast<float>(R(i, 2));
      c.up[i] = static_cast<float>(-R(i, 1));
    }
    c.frustum_near = static_cast<float>(n);
    c.frustum_far = static_cast<float>(settings.far_m);
    c.frustum_top = static_cast<float>(n * k.cy_px / k.fy_px);
    c.frustum_bottom = static_cast<float>(-n * (k.height_px - k.cy_px) / k.fy_px);
    c.frustum_center = static_cast<float>(n * (0.5 * k.width_px - k.cx_px) / k.fx_px);
  }
}

/// OpenGL window depth d in [0, 1] (bottom-up rows) -> z along the optical axis [m] (top-down rows).
void LinearDepth(const std::vector<float>& raw, const CameraIntrinsics& k, const RenderSettings& settings,
                 std::vector<float>* depth_m) {
  const double n = settings.near_m, f = settings.far_m;
  depth_m->resize(raw.size());
  for (int y = 0; y < k.height_px; ++y) {
    for (int x = 0; x < k.width_px; ++x) {
      const double d = raw[static_cast<std::size_t>((k.height_px - 1 - y) * k.width_px + x)];
      (*depth_m)[static_cast<std::size_t>(y * k.width_px + x)] = static_cast<float>(n * f / (f - d * (f - n)));
    }
  }
}

}  // namespace

struct OffscreenRenderer::Impl {
  OSMesaContext gl = nullptr;
  std::vector<unsigned char> gl_buffer;  ///< OSMesa's default framebuffer (MuJoCo draws offscreen)
  int gl_width = 0, gl_height = 0;
  const mjModel* model = nullptr;
  mjrContext context;
  mjvScene scene;
  bool context_made = false, scene_made = false;
  int max_width = 0, max_height = 0;

  bool MakeCurrent() {
    return OSMesaMakeCurrent(gl, gl_buffer.data(), GL_UNSIGNED_BYTE, gl_width, gl_height) == GL_TRUE;
  }
};

bool CameraIntrinsics::Validate(std::string* error) const {
  const auto fail = [&](const std::string& what) {
    if (error) *error = "camera intrinsics: " + what;
    return false;
  };
  if (width_px < 1 || height_px < 1) return fail("width_px and height_px must be >= 1");
  if (!(fx_px > 0.0 && fy_px > 0.0)) return fail("fx_px and fy_px must be > 0");
  if (std::abs(fx_px - fy_px) > 1e-9 * fx_px) return fail("fx_px must equal fy_px (square pixels)");
  if (!std::isfinite(cx_px) || !std::isfinite(cy_px)) return fail("cx_px, cy_px must be finite");
  return true;
}

Status OffscreenRenderer::Create(mjModel* model, int max_width_px, int max_height_px, int multisamples,
                                 std::unique_ptr<OffscreenRenderer>* out) {
  ROTOLIDAR_CHECK(model != nullptr && out != nullptr, "OffscreenRenderer::Create needs a model and an output");
  if (max_width_px < 1 || max_height_px < 1 || max_width_px > 8192 || max_height_px > 8192) {
    return Status::Error("offscreen renderer: image size must be in [1, 8192]");
  }
  std::unique_ptr<OffscreenRenderer> r(new OffscreenRenderer());
  r->impl_ = std::make_unique<Impl>();
  Impl& impl = *r->impl_;
  impl.gl = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (!impl.gl) return Status::Error("offscreen renderer: OSMesaCreateContextExt failed");
  impl.gl_width = impl.gl_height = 16;  // MuJoCo renders into its own framebuffer object
  impl.gl_buffer.assign(static_cast<std::size_t>(4 * impl.gl_width * impl.gl_height), 0);
  if (!impl.MakeCurrent()) return Status::Error("offscreen renderer: OSMesaMakeCurrent failed");
  model->vis.global.offwidth = max_width_px;
  model->vis.global.offheight = max_height_px;
  model->vis.quality.offsamples = std::clamp(multisamples, 0, 16);
  mjr_defaultContext(&impl.context);
  mjr_makeContext(model, &impl.context, mjFONTSCALE_100);
  impl.context_made = true;
  mjr_setBuffer(mjFB_OFFSCREEN, &impl.context);
  if (impl.context.currentBuffer != mjFB_OFFSCREEN) {
    return Status::Error("offscreen renderer: MuJoCo has no offscreen framebuffer");
  }
  mjv_defaultScene(&impl.scene);
  mjv_makeScene(model, &impl.scene, model->ngeom + 64);
  impl.scene_made = true;
  impl.model = model;
  impl.max_width = max_width_px;
  impl.max_height = max_height_px;
  *out = std::move(r);
  return Status::Ok();
}

OffscreenRenderer::~OffscreenRenderer() {
  if (!impl_) return;
  if (impl_->gl) impl_->MakeCurrent();
  if (impl_->scene_made) mjv_freeScene(&impl_->scene);
  if (impl_->context_made) mjr_freeContext(&impl_->context);
  if (impl_->gl) OSMesaDestroyContext(impl_->gl);
}

Status OffscreenRenderer::Render(const mjModel* model, mjData* data, const Eigen::Isometry3d& T_world_cam,
                                 const CameraIntrinsics& k, const RenderSettings& settings, RgbImage* rgb,
                                 std::vector<float>* depth_m) {
  ROTOLIDAR_CHECK(model == impl_->model && data != nullptr && rgb != nullptr, "Render: wrong model or no output");
  std::string error;
  if (!k.Validate(&error)) return Status::Error(error);
  if (k.width_px > impl_->max_width || k.height_px > impl_->max_height) {
    return Status::Error("offscreen renderer: image larger than the maxima given to Create");
  }
  if (!(settings.near_m > 0.0 && settings.far_m > settings.near_m)) {
    return Status::Error("offscreen renderer: need 0 < near_m < far_m");
  }
  if (!impl_->MakeCurrent()) return Status::Error("offscreen renderer: OSMesaMakeCurrent failed");
  mjvOption option;
  mjv_defaultOption(&option);
  for (int g = 0; g < 6; ++g) option.geomgroup[g] = settings.geom_groups[static_cast<std::size_t>(g)];
  mjvCamera camera;
  mjv_defaultCamera(&camera);
  mjvPerturb perturb;
  mjv_defaultPerturb(&perturb);
  mjv_updateScene(model, data, &option, &perturb, &camera, mjCAT_ALL, &impl_->scene);
  mjvScene& scn = impl_->scene;
  scn.flags[mjRND_SHADOW] = settings.shadows;
  scn.flags[mjRND_SKYBOX] = settings.skybox;
  scn.flags[mjRND_REFLECTION] = 0;
  SetGlCamera(T_world_cam, k, settings, &scn);
  const mjrRect viewport{0, 0, k.width_px, k.height_px};
  mjr_setBuffer(mjFB_OFFSCREEN, &impl_->context);
  mjr_render(viewport, &scn, &impl_->context);
  const std::size_t pixels = static_cast<std::size_t>(k.width_px) * static_cast<std::size_t>(k.height_px);
  std::vector<unsigned char> bottom_up(3 * pixels);
  std::vector<float> depth_raw(depth_m ? pixels : 0);
  mjr_readPixels(bottom_up.data(), depth_m ? depth_raw.data() : nullptr, viewport, &impl_->context);
  rgb->width = k.width_px;
  rgb->height = k.height_px;
  rgb->rgb.resize(3 * pixels);
  const std::size_t row = 3 * static_cast<std::size_t>(k.width_px);
  for (int y = 0; y < k.height_px; ++y) {  // OpenGL rows run bottom to top
    std::copy_n(&bottom_up[row * static_cast<std::size_t>(k.height_px - 1 - y)], row, &rgb->rgb[row * y]);
  }
  if (depth_m) LinearDepth(depth_raw, k, settings, depth_m);
  return Status::Ok();
}

Eigen::Isometry3d LookAt(const Eigen::Vector3d& eye_m, const Eigen::Vector3d& target_m) {
  const Eigen::Vector3d z = (target_m - eye_m).normalized();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  if (std::abs(z.dot(up)) > 0.999) up = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = z.cross(up).normalized();  // image right
  const Eigen::Vector3d y = z.cross(x);                // image down
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = eye_m;
  return T;
}

}  // namespace rotolidar::sim
