#pragma once
// Procedural textures for the camera: a scene names a texture per material (docs/scene_format.md); the name is
// looked up first in the scene's own `textures:` list, then in a built-in library. Every texture is generated
// deterministically from its spec (the same spec gives the same bytes), so nothing binary lives in scenes/.
//
// A texture image covers a square of `size_m` x `size_m` metres on a surface and repeats; its colours are
// multiplied by the material's `color` when rendered (built-ins carry their own colours, materials default to
// white when textured).
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace rotolidar::sim {

enum class TexturePattern {
  kFlat,      ///< color_a everywhere (plus grain)
  kNoise,     ///< multi-scale value noise blending color_a towards color_b (plaster, concrete, asphalt, grass)
  kChecker,   ///< cells x cells checkerboard of color_a / color_b
  kBricks,    ///< `cells` courses of bricks (color_a), half-offset rows, mortar lines (color_b)
  kTiles,     ///< cells x cells square tiles (color_a) with grout lines (color_b)
  kPlanks,    ///< `cells` horizontal planks with grain streaks (wood floors, doors)
  kStripes,   ///< `cells` vertical stripes alternating color_a / color_b
  kFacade,    ///< cells x cells windows (color_b) on a wall (color_a): building fronts
  kMarkings,  ///< asphalt (color_a) with `cells` painted bay lines (color_b) across the image, parking bays
};

/// The patterns' words in scene files: "flat", "noise", "checker", "bricks", "tiles", "planks", "stripes",
/// "facade", "markings" (core/io/yaml_fields.hpp finds it by argument-dependent lookup).
const std::vector<std::pair<const char*, TexturePattern>>& EnumWords(TexturePattern*);
/// Parses one of those words; false for anything else.
bool ParseTexturePattern(const std::string& name, TexturePattern* pattern);
const char* TexturePatternName(TexturePattern pattern);

struct TextureSpec {
  std::string name;
  TexturePattern pattern = TexturePattern::kNoise;
  Eigen::Vector3d color_a = Eigen::Vector3d(0.8, 0.8, 0.8);  ///< main colour, RGB in [0, 1]
  Eigen::Vector3d color_b = Eigen::Vector3d(0.5, 0.5, 0.5);  ///< secondary colour (lines, mortar, windows)
  double size_m = 1.0;     ///< the image covers size_m x size_m metres of surface (> 0)
  int cells = 8;           ///< pattern repeats inside one image (rows, tiles, stripes...), >= 1
  double grain = 0.15;     ///< amplitude of the fine noise added to every pattern, [0, 1]
  int resolution_px = 128; ///< image width = height, in [8, 1024]

  /// On failure names the texture and the field.
  bool Validate(std::string* error) const;
};

/// An 8-bit RGB image, rows top to bottom, 3 bytes per pixel.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  ///< width * height * 3 bytes
};

/// The built-in textures (plaster, wood_floor, ceiling, concrete, bricks, asphalt, ...), fixed order.
const std::vector<TextureSpec>& BuiltinTextures();

/// `name` in `scene_textures` first, then among the built-ins; nullptr when neither has it.
const TextureSpec* FindTexture(const std::vector<TextureSpec>& scene_textures, const std::string& name);

/// Generates the image (deterministic: its noise stream is seeded from the texture's name). The spec must be
/// valid (programmer error otherwise).
RgbImage RenderTexture(const TextureSpec& spec);

}  // namespace rotolidar::sim
