#pragma once
// `rotolidar scene list|show`: scene sizes and load times, and pictures a user can look at (a top view and a
// perspective view rendered offscreen with MuJoCo/OSMesa from the same loaded Scene the LiDAR sees), plus the
// truth file of the scene's annotated elements.
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/util/status.hpp"

namespace rotolidar::bench {

/// One scene file, loaded and measured.
struct SceneInfo {
  std::string name;      ///< the scene's name (file name without .yaml when the file names none)
  std::string path;
  bool ok = false;
  std::string error;     ///< when !ok: the loader's message
  std::size_t static_triangles = 0;
  std::size_t dynamic_triangles = 0;   ///< all dynamic objects' bodies together
  std::size_t primitives = 0, meshes = 0, elements = 0, dynamic_objects = 0;
  Eigen::AlignedBox3d extent;          ///< bounds of the static triangles [m, world]
  bool closed = false;
  std::vector<std::string> carriers;   ///< keys of default_paths
  double load_ms = 0.0;     ///< LoadScene (YAML + mesh files)
  double embree_ms = 0.0;   ///< BuildMesh + EmbreeScene::Create (with dynamic instances)
  double set_time_us = 0.0; ///< median EmbreeScene::SetTime (move all dynamic objects, recommit); 0 without any
};

/// Loads and measures one scene file (never fails: errors land in SceneInfo::error).
SceneInfo MeasureScene(const std::string& path);

/// Every *.yaml in `dir`, sorted by file name, measured. Fails only when `dir` cannot be listed.
Status ListScenes(const std::string& dir, std::vector<SceneInfo>* infos);

struct SceneShowOptions {
  std::string out_dir = ".";  ///< created when missing
  int width_px = 800;
  int height_px = 600;
  double time_s = 0.0;        ///< where dynamic objects are drawn
  int multisamples = 4;       ///< anti-aliasing samples of the offscreen buffer (0..16)
  bool shadows = false;
  int color_bits = 8;         ///< bits kept per colour channel in the PNGs (1..8); fewer = smaller files
};

struct SceneShowResult {
  std::string top_png;          ///< <out>/<name>_top.png: straight down, ceilings and roofs left out
  std::string perspective_png;  ///< <out>/<name>_perspective.png: the scene's `view`, or an oblique default
  std::string elements_csv;     ///< <out>/<name>_elements.csv: WriteElementTruth
  double render_ms = 0.0;       ///< both pictures
};

/// Loads `name_or_path` (a scene name in scenes/ or a file), builds its MuJoCo model and renders both views.
/// The top view uses a neutral plan light (headlight ambient 0.45, diffuse 0.5) so dark scenes stay
/// readable; the perspective view uses the scene's own lighting. Fails naming the file or the step.
Status ShowScene(const std::string& name_or_path, const SceneShowOptions& options, SceneShowResult* result);

}  // namespace rotolidar::bench
