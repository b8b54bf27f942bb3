// Ray-cast camera: per-pixel rays through the lens, texture frames per triangle, Lambert shading with the scene's
// lights (contract in embree_camera.hpp).
#include "sim/camera/embree_camera.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "sim/world/scene_dynamic.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

/// A texture as albedo bytes (RGBX, 4 bytes a texel: one aligned load per tap), with its mip levels (each half
/// the size of the one before, box-filtered).
struct MipTexture {
  std::vector<int> sizes;                    ///< level width = height [texels]
  std::vector<std::vector<uint8_t>> levels;  ///< RGBX per level
  float tiles_per_m = 1.0f;                  ///< 1 / size_m
};

MipTexture MakeMipTexture(const TextureSpec& spec) {
  const RgbImage image = RenderTexture(spec);
  cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<uint8_t*>(image.rgb.data())), level;
  cv::cvtColor(rgb, level, cv::COLOR_RGB2RGBA);
  MipTexture t;
  t.tiles_per_m = static_cast<float>(1.0 / spec.size_m);
  while (true) {
    t.sizes.push_back(level.cols);
    t.levels.emplace_back(level.ptr<uint8_t>(), level.ptr<uint8_t>() + 4 * level.total());
    if (level.cols == 1) break;
    cv::Mat half;
    const int n = std::max(1, (level.cols + 1) / 2);
    cv::resize(level, half, cv::Size(n, n), 0, 0, cv::INTER_AREA);
    level = half;
  }
  return t;
}

int FloorToInt(float x) {  // std::floor is a libm call without SSE4.1
  const int i = static_cast<int>(x);
  return x < static_cast<float>(i) ? i - 1 : i;
}

/// Bilinear, wrapping lookup of level `l` at texture coordinates (s, t) in tiles.
Eigen::Array3f SampleLevel(const MipTexture& tex, int l, float s, float t) {
  const int n = tex.sizes[static_cast<std::size_t>(l)];
  const float x = (s - static_cast<float>(FloorToInt(s))) * n - 0.5f;  // in [-0.5, n - 0.5)
  const float y = (t - static_cast<float>(FloorToInt(t))) * n - 0.5f;
  const int x0 = FloorToInt(x), y0 = FloorToInt(y);  // in [-1, n - 1]
  const float fx = x - x0, fy = y - y0;
  const int xa = x0 < 0 ? n - 1 : x0, ya = y0 < 0 ? n - 1 : y0;
  const int xb = x0 + 1 >= n ? 0 : x0 + 1, yb = y0 + 1 >= n ? 0 : y0 + 1;
  const uint8_t* d = tex.levels[static_cast<std::size_t>(l)].data();
  const uint8_t* p00 = d + 4 * (ya * n + xa);
  const uint8_t* p01 = d + 4 * (ya * n + xb);
  const uint8_t* p10 = d + 4 * (yb * n + xa);
  const uint8_t* p11 = d + 4 * (yb * n + xb);
  const float w00 = (1 - fx) * (1 - fy), w01 = fx * (1 - fy), w10 = (1 - fx) * fy, w11 = fx * fy;
  Eigen::Array3f out;
  for (int c = 0; c < 3; ++c) out[c] = (w00 * p00[c] + w01 * p01[c] + w10 * p10[c] + w11 * p11[c]) * (1.0f / 255.0f);
  return out;
}

/// Trilinear lookup: `texels_per_px` is the pixel's footprint in level-0 texels.
Eigen::Array3f SampleMip(const MipTexture& tex, float s, float t, float texels_per_px) {
  const int last = static_cast<int>(tex.sizes.size()) - 1;
  const float lod = std::clamp(std::log2(std::max(texels_per_px, 1.0f)), 0.0f, static_cast<float>(last));
  const int l0 = static_cast<int>(lod);
  const float f = lod - l0;
  const Eigen::Array3f a = SampleLevel(tex, l0, s, t);
  if (f < 1e-3f || l0 == last) return a;
  return (1 - f) * a + f * SampleLevel(tex, l0 + 1, s, t);
}

/// Where a triangle's texture lies: texture coordinates [tiles] = ((p - origin) . col, (p - origin) . row) times
/// the texture's tiles_per_m.
struct TextureFrame {
  Eigen::Vector3f origin, col, row;
};

std::vector<TextureFrame> TextureFrames(const TriangleMesh& mesh, const std::vector<Primitive>& primitives) {
  std::vector<TextureFrame> frames(mesh.triangles.size());
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Eigen::Vector3i& tri = mesh.triangles[i];
    const Eigen::Vector3d& a = mesh.vertices_m[tri[0]];
    const Eigen::Vector3d n = (mesh.vertices_m[tri[1]] - a).cross(mesh.vertices_m[tri[2]] - a).normalized();
    const int id = mesh.primitive_ids[i];
    const Primitive* p = id >= 0 && id < static_cast<int>(primitives.size()) ? &primitives[static_cast<std::size_t>(id)]
                                                                               : nullptr;
    Eigen::Vector3d col, row;
    if (std::abs(n.z()) < 0.7) {  // a wall: texture rows run down the surface
      row = -(Eigen::Vector3d::UnitZ() - n.z() * n).normalized();
      col = n.cross(row);
    } else {  // a floor or ceiling: columns along the primitive's x axis
      const Eigen::Matrix3d R = p ? p->Rotation() : Eigen::Matrix3d::Identity();
      col = R.col(0) - R.col(0).dot(n) * n;
      if (col.norm() < 1e-6) col = R.col(1) - R.col(1).dot(n) * n;
      col.normalize();
      row = col.cross(n);
    }
    frames[i] = {(p ? p->center_m : a).cast<float>(), col.cast<float>(), row.cast<float>()};
  }
  return frames;
}

struct Light {
  Eigen::Vector3f position, direction;  ///< direction: unit, where it shines
  float intensity = 0.0f;
  bool directional = false, shadow = false;
};

constexpr float kSpotCosCutoff = 0.70710678f;  // MuJoCo's default cutoff: 45 deg
constexpr double kShadowBias_m = 2e-3;

/// Irradiance from one light at point p with normal n; *to_light: unit direction, *distance_m its range.
inline float LightTerm(const Light& light, const Eigen::Vector3f& p, const Eigen::Vector3f& n, Eigen::Vector3f* to_light,
                float* distance_m) {
  if (light.directional) {
    *to_light = -light.direction;
    *distance_m = 1e30f;
    return light.intensity * std::max(0.0f, n.dot(*to_light));
  }
  const Eigen::Vector3f v = light.position - p;
  *distance_m = v.norm();
  const float inv = 1.0f / *distance_m;
  const float c = -v.dot(light.direction) * inv;  // cosine to the spot's axis
  if (c < kSpotCosCutoff) return 0.0f;
  const float ndotl = n.dot(v) * inv;
  if (ndotl <= 0.0f) return 0.0f;
  *to_light = v * inv;
  const float c2 = c * c, c4 = c2 * c2;
  return light.intensity * c4 * c4 * c2 * ndotl;  // spot exponent 10
}

}  // namespace

struct EmbreeCameraRenderer::Impl {
  EmbreeScene* embree = nullptr;
  CameraConfig config;
  rotolidar::CameraIntrinsics intrinsics;
  std::vector<MipTexture> textures;
  std::vector<int> material_texture;           ///< per material: index into textures or -1
  std::vector<Eigen::Array3f> material_color;  ///< per material: visible albedo colour
  std::vector<TextureFrame> static_frames;
  std::vector<std::vector<TextureFrame>> object_frames;
  std::vector<Light> lights;
  float ambient = 0.0f, headlight = 0.0f;
  Eigen::Array3f sky = Eigen::Array3f::Zero();

  void RenderRow(int v, const Pose3& T_world_cam, const PixelRayTable& rays, RadianceImage* out) const;
  /// Adds a shadow-casting light's irradiance where a shadow ray reaches it (one batch for the row).
  void AddShadowedLight(const Light& light, const std::vector<RayHit>& hits, const std::vector<Eigen::Vector3d>& points,
                        std::vector<RayQuery>* queries, std::vector<float>* irradiance) const;
  Eigen::Array3f Albedo(const RayHit& hit, const Eigen::Vector3d& p_world, float texels_scale) const;
};

EmbreeCameraRenderer::~EmbreeCameraRenderer() = default;

Status EmbreeCameraRenderer::Create(const Scene& scene, EmbreeScene* embree, const CameraConfig& config,
                                    std::unique_ptr<EmbreeCameraRenderer>* out) {
  ROTOLIDAR_CHECK(embree != nullptr && out != nullptr, "EmbreeCameraRenderer::Create needs a scene and an output");
  std::string why;
  if (!config.Validate(&why)) return Status::Error("embree camera: " + why);
  std::unique_ptr<EmbreeCameraRenderer> r(new EmbreeCameraRenderer());
  r->impl_ = std::make_unique<Impl>();
  Impl& m = *r->impl_;
  m.embree = embree;
  m.config = config;
  m.intrinsics = config.Intrinsics();
  r->rays_ = MakePixelRayTable(m.intrinsics);
  for (const Material& mat : embree->materials()) {
    m.material_color.push_back(mat.color_rgb.cast<float>().array());
    m.material_texture.push_back(-1);
    if (mat.texture.empty()) continue;
    const TextureSpec* spec = FindTexture(scene.textures, mat.texture);
    if (!spec) return Status::Error("embree camera: material '" + mat.name + "': no texture '" + mat.texture + "'");
    m.material_texture.back() = static_cast<int>(m.textures.size());
    m.textures.push_back(MakeMipTexture(*spec));
  }
  m.static_frames = TextureFrames(BuildMesh(scene), scene.primitives);
  for (const DynamicObject& object : scene.dynamic_objects)
    m.object_frames.push_back(TextureFrames(BuildObjectMesh(scene, object), object.parts));
  if (m.object_frames.size() != embree->num_dynamic_objects())
    return Status::Error("embree camera: the Embree scene was not built from this scene (dynamic objects differ)");
  const SceneLighting& l = scene.lighting;
  m.ambient = static_cast<float>(l.ambient);
  m.headlight = static_cast<float>(l.headlight);
  m.sky = l.sky_rgb.cast<float>().array();
  for (const SceneLight& s : l.lights) {
    m.lights.push_back({s.position_m.cast<float>(), s.direction.normalized().cast<float>(),
                        static_cast<float>(s.intensity), s.directional, s.cast_shadow && config.shadows});
  }
  *out = std::move(r);
  return Status::Ok();
}

Eigen::Array3f EmbreeCameraRenderer::Impl::Albedo(const RayHit& hit, const Eigen::Vector3d& p_world,
                                                  float texels_scale) const {
  const std::size_t mat = static_cast<std::size_t>(hit.material_id);
  const int tex = material_texture[mat];
  if (tex < 0) return material_color[mat];
  const TextureFrame* frame;
  Eigen::Vector3f p;
  if (hit.object_id < 0) {
    frame = &static_frames[static_cast<std::size_t>(hit.triangle_id)];
    p = p_world.cast<float>();
  } else {
    const std::size_t k = static_cast<std::size_t>(hit.object_id);
    frame = &object_frames[k][static_cast<std::size_t>(hit.triangle_id)];
    p = (embree->object_pose(k).inverse() * p_world).cast<float>();
  }
  const MipTexture& t = textures[static_cast<std::size_t>(tex)];
  const Eigen::Vector3f d = p - frame->origin;
  const float texels_per_px = texels_scale * t.tiles_per_m * static_cast<float>(t.sizes[0]);
  return material_color[mat] * SampleMip(t, d.dot(frame->col) * t.tiles_per_m, d.dot(frame->row) * t.tiles_per_m,
                                         texels_per_px);
}

void EmbreeCameraRenderer::Impl::AddShadowedLight(const Light& light, const std::vector<RayHit>& hits,
                                                  const std::vector<Eigen::Vector3d>& points,
                                                  std::vector<RayQuery>* queries,
                                                  std::vector<float>* irradiance) const {
  std::vector<float> term(queries->size(), 0.0f);
  for (std::size_t i = 0; i < queries->size(); ++i) {
    (*queries)[i].t_max_m = 0.0;  // no shadow ray
    if (!hits[i].hit) continue;
    Eigen::Vector3f l;
    float distance;
    term[i] = LightTerm(light, points[i].cast<float>(), hits[i].normal_world.cast<float>(), &l, &distance);
    if (term[i] > 0.0f)
      (*queries)[i] = {points[i] + kShadowBias_m * hits[i].normal_world, l.cast<double>(),
                       std::min<double>(distance, config.max_range_m) - kShadowBias_m};
  }
  std::vector<RayHit> blockers(queries->size());
  embree->IntersectBatch(queries->data(), queries->size(), blockers.data());
  for (std::size_t i = 0; i < queries->size(); ++i)
    if (!blockers[i].hit) (*irradiance)[i] += term[i];
}

void EmbreeCameraRenderer::Impl::RenderRow(int v, const Pose3& T_world_cam, const PixelRayTable& rays,
                                           RadianceImage* out) const {
  const int w = rays.width;
  const Eigen::Matrix3d R = T_world_cam.linear();
  const Eigen::Vector3d origin = T_world_cam.translation();
  const Eigen::Vector3f forward = R.col(2).cast<float>();
  std::vector<RayQuery> queries(static_cast<std::size_t>(w));
  std::vector<RayHit> hits(queries.size());
  std::vector<float> ray_norm(queries.size());
  for (int u = 0; u < w; ++u) {
    const Eigen::Vector2f& xy = rays.at(u, v);
    const Eigen::Vector3d ray(xy.x(), xy.y(), 1.0);
    ray_norm[static_cast<std::size_t>(u)] = static_cast<float>(ray.norm());
    queries[static_cast<std::size_t>(u)] = {origin, R * ray, config.max_range_m};
  }
  embree->IntersectBatch(queries.data(), queries.size(), hits.data());
  // Irradiance per pixel; lights that cast shadows are checked with one more batch of rays each.
  std::vector<float> irradiance(queries.size(), 0.0f);
  std::vector<Eigen::Vector3d> points(queries.size());
  const float f_px = static_cast<float>(std::min(intrinsics.fx_px, intrinsics.fy_px));
  for (int u = 0; u < w; ++u) {
    const std::size_t i = static_cast<std::size_t>(u);
    const RayHit& hit = hits[i];
    float* px = &out->rgb[3 * (static_cast<std::size_t>(v) * w + i)];
    if (!hit.hit) {
      const float up = static_cast<float>(queries[i].dir_world.normalized().z());
      Eigen::Array3f::Map(px) = sky * (0.8f + 0.2f * up);
      out->depth_m[static_cast<std::size_t>(v) * w + i] = 0.0f;
      continue;
    }
    const Eigen::Vector3d dir = queries[i].dir_world / queries[i].dir_world.norm();
    points[i] = origin + hit.distance_m * dir;
    const Eigen::Vector3f n = hit.normal_world.cast<float>();
    const float cos_view = std::max(0.25f, static_cast<float>(-hit.normal_world.dot(dir)));
    irradiance[i] = ambient + headlight * std::max(0.0f, -n.dot(forward));
    const Eigen::Vector3f p = points[i].cast<float>();
    for (const Light& light : lights) {
      Eigen::Vector3f l;
      float distance;
      if (!light.shadow) irradiance[i] += LightTerm(light, p, n, &l, &distance);  // shadowed ones: below
    }
    const float footprint_m = static_cast<float>(hit.distance_m) / (f_px * cos_view);
    const Eigen::Array3f albedo = Albedo(hit, points[i], footprint_m);
    Eigen::Array3f::Map(px) = albedo;  // times the irradiance once shadows are known
    out->depth_m[static_cast<std::size_t>(v) * w + i] = static_cast<float>(hit.distance_m) / ray_norm[i];
  }
  for (const Light& light : lights)
    if (light.shadow) AddShadowedLight(light, hits, points, &queries, &irradiance);
  for (int u = 0; u < w; ++u) {
    const std::size_t i = static_cast<std::size_t>(u);
    if (!hits[i].hit) continue;
    float* px = &out->rgb[3 * (static_cast<std::size_t>(v) * w + i)];
    for (int c = 0; c < 3; ++c) px[c] *= irradiance[i];
  }
}

Status EmbreeCameraRenderer::Render(Seconds t_s, const std::vector<Pose3>& T_world_cam_rows, RadianceImage* out) {
  const int h = rays_.height;
  if (T_world_cam_rows.size() != 1 && T_world_cam_rows.size() != static_cast<std::size_t>(h))
    return Status::Error("embree camera: need 1 or " + std::to_string(h) + " poses, got " +
                         std::to_string(T_world_cam_rows.size()));
  impl_->embree->SetTime(t_s);
  out->Resize(rays_.width, h);
  ParallelRows(h, impl_->config.threads, 4, [&](int v0, int v1) {
    for (int v = v0; v < v1; ++v)
      impl_->RenderRow(v, T_world_cam_rows[T_world_cam_rows.size() == 1 ? 0 : static_cast<std::size_t>(v)], rays_, out);
  });
  return Status::Ok();
}

}  // namespace rotolidar::sim
