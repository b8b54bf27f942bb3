// Procedural, tileable textures: value noise plus simple architectural patterns, so the camera finds features.
#include "sim/world/texture.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::sim {
namespace {

/// Tileable multi-octave value noise on [0,1)^2 with values in [0, 1]: random lattices of 4, 8, 16 and 32
/// cells per image (wrapping at the borders), smoothstep-interpolated, weights halving per octave.
class TileNoise {
 public:
  explicit TileNoise(const std::string& stream) {
    RandomStream rng(0, "sim.texture." + stream);
    for (int octave = 0; octave < kOctaves; ++octave) {
      const int n = 4 << octave;
      lattices_[octave].resize(static_cast<std::size_t>(n * n));
      for (double& v : lattices_[octave]) v = rng.Uniform();
    }
  }

  double operator()(double u, double v) const {
    double sum = 0.0, weight = 1.0, total = 0.0;
    for (int octave = 0; octave < kOctaves; ++octave) {
      sum += weight * Sample(octave, u, v);
      total += weight;
      weight *= 0.5;
    }
    return sum / total;
  }

 private:
  static constexpr int kOctaves = 4;

  double Sample(int octave, double u, double v) const {
    const int n = 4 << octave;
    const double x = u * n, y = v * n;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = Smooth(x - x0), fy = Smooth(y - y0);
    const auto at = [&](int i, int j) {
      return lattices_[octave][static_cast<std::size_t>(((j % n + n) % n) * n + (i % n + n) % n)];
    };
    const double a = at(x0, y0) + fx * (at(x0 + 1, y0) - at(x0, y0));
    const double b = at(x0, y0 + 1) + fx * (at(x0 + 1, y0 + 1) - at(x0, y0 + 1));
    return a + fy * (b - a);
  }
  static double Smooth(double t) { return t * t * (3.0 - 2.0 * t); }

  std::vector<double> lattices_[kOctaves];
};

/// True within `half_width` (fraction of a cell) of a cell border, for `cells` cells across [0, 1).
bool NearLine(double u, int cells, double half_width) {
  const double f = u * cells - std::floor(u * cells);
  return f < half_width || f > 1.0 - half_width;
}

/// Weight of color_b at (u, v) for the pattern, in [0, 1] (v grows downwards in the image).
double PatternWeight(const TextureSpec& s, const TileNoise& noise, double u, double v) {
  const int n = s.cells;
  switch (s.pattern) {
    case TexturePattern::kFlat: return 0.0;
    case TexturePattern::kNoise: return noise(u, v);
    case TexturePattern::kChecker:
      return ((static_cast<int>(u * n) + static_cast<int>(v * n)) % 2) ? 1.0 : 0.0;
    case TexturePattern::kBricks: {
      const int row = static_cast<int>(v * n);
      const double shifted = u + ((row % 2) ? 0.5 / (n / 2.0) : 0.0);  // bricks are twice as wide as tall
      return (NearLine(v, n, 0.06) || NearLine(shifted, std::max(1, n / 2), 0.03)) ? 1.0 : 0.0;
    }
    case TexturePattern::kTiles: return (NearLine(u, n, 0.03) || NearLine(v, n, 0.03)) ? 1.0 : 0.0;
    case TexturePattern::kPlanks: {
      const int row = static_cast<int>(v * n);
      const double streak = 0.5 + 0.5 * std::sin(2.0 * 3.14159265358979 * (u * 3.0 + row * 0.37) +
                                                  8.0 * noise(u, v * 0.25 + row * 0.13));
      return NearLine(v, n, 0.025) ? 1.0 : 0.45 * streak;
    }
    case TexturePattern::kStripes: return (static_cast<int>(u * n) % 2) ? 1.0 : 0.0;
    case TexturePattern::kFacade: {
      const double fu = u * n - std::floor(u * n), fv = v * n - std::floor(v * n);
      return (fu > 0.2 && fu < 0.8 && fv > 0.25 && fv < 0.75) ? 1.0 : 0.0;
    }
    case TexturePattern::kMarkings:
      return (NearLine(u, n, 0.012 * n) || v > 0.97) ? 1.0 : 0.2 * noise(u, v);
  }
  return 0.0;
}

uint8_t ToByte(double x) { return static_cast<uint8_t>(std::lround(255.0 * std::clamp(x, 0.0, 1.0))); }

TextureSpec Builtin(const std::string& name, TexturePattern p, Eigen::Vector3d a, Eigen::Vector3d b, double size_m,
                    int cells, double grain) {
  TextureSpec s;
  s.name = name;
  s.pattern = p;
  s.color_a = a;
  s.color_b = b;
  s.size_m = size_m;
  s.cells = cells;
  s.grain = grain;
  return s;
}

}  // namespace

const std::vector<std::pair<const char*, TexturePattern>>& EnumWords(TexturePattern*) {
  static const std::vector<std::pair<const char*, TexturePattern>> words{
      {"flat", TexturePattern::kFlat},       {"noise", TexturePattern::kNoise},
      {"checker", TexturePattern::kChecker}, {"bricks", TexturePattern::kBricks},
      {"tiles", TexturePattern::kTiles},     {"planks", TexturePattern::kPlanks},
      {"stripes", TexturePattern::kStripes}, {"facade", TexturePattern::kFacade},
      {"markings", TexturePattern::kMarkings},
  };
  return words;
}

bool ParseTexturePattern(const std::string& name, TexturePattern* pattern) {
  for (const auto& [word, p] : EnumWords(pattern))
    if (name == word) return *pattern = p, true;
  return false;
}

const char* TexturePatternName(TexturePattern pattern) {
  for (const auto& [word, p] : EnumWords(&pattern))
    if (p == pattern) return word;
  return "?";
}

bool TextureSpec::Validate(std::string* error) const {
  const auto fail = [&](const std::string& what) {
    if (error) *error = "texture '" + name + "': " + what;
    return false;
  };
  if (name.empty()) return fail("name is empty");
  for (const Eigen::Vector3d* c : {&color_a, &color_b}) {
    if (!(c->minCoeff() >= 0.0 && c->maxCoeff() <= 1.0)) return fail("colors must be in [0, 1]");
  }
  if (!(size_m > 0.0 && std::isfinite(size_m))) return fail("size must be > 0");
  if (cells < 1 || cells > 256) return fail("cells must be in [1, 256]");
  if (!(grain >= 0.0 && grain <= 1.0)) return fail("grain must be in [0, 1]");
  if (resolution_px < 8 || resolution_px > 1024) return fail("resolution must be in [8, 1024]");
  return true;
}

const std::vector<TextureSpec>& BuiltinTextures() {
  using V = Eigen::Vector3d;
  using P = TexturePattern;
  static const std::vector<TextureSpec> kBuiltins = {
      Builtin("plaster", P::kNoise, V(0.90, 0.89, 0.85), V(0.70, 0.69, 0.66), 2.0, 8, 0.10),
      Builtin("wood_floor", P::kPlanks, V(0.62, 0.45, 0.28), V(0.35, 0.24, 0.14), 2.0, 10, 0.12),
      Builtin("ceiling", P::kTiles, V(0.93, 0.93, 0.92), V(0.55, 0.55, 0.55), 2.4, 4, 0.06),
      Builtin("fabric_dark", P::kNoise, V(0.22, 0.24, 0.30), V(0.10, 0.11, 0.15), 0.5, 8, 0.25),
      Builtin("laminate", P::kPlanks, V(0.85, 0.80, 0.70), V(0.60, 0.55, 0.45), 1.0, 6, 0.08),
      Builtin("concrete", P::kNoise, V(0.70, 0.70, 0.68), V(0.45, 0.45, 0.44), 2.0, 8, 0.20),
      Builtin("door", P::kPlanks, V(0.55, 0.38, 0.22), V(0.30, 0.20, 0.11), 1.0, 4, 0.10),
      Builtin("exit_sign", P::kChecker, V(0.10, 0.70, 0.30), V(0.95, 0.95, 0.95), 0.6, 3, 0.05),
      Builtin("bricks", P::kBricks, V(0.62, 0.30, 0.22), V(0.80, 0.78, 0.72), 1.2, 16, 0.20),
      Builtin("asphalt", P::kNoise, V(0.30, 0.30, 0.31), V(0.16, 0.16, 0.17), 3.0, 8, 0.30),
      Builtin("parking_lines", P::kMarkings, V(0.30, 0.30, 0.31), V(0.92, 0.92, 0.88), 10.0, 4, 0.25),
      Builtin("road", P::kMarkings, V(0.27, 0.27, 0.28), V(0.90, 0.85, 0.40), 6.0, 1, 0.25),
      Builtin("sidewalk", P::kTiles, V(0.68, 0.66, 0.62), V(0.45, 0.44, 0.42), 2.0, 4, 0.18),
      Builtin("grass", P::kNoise, V(0.30, 0.55, 0.20), V(0.15, 0.32, 0.10), 2.0, 8, 0.35),
      Builtin("bark", P::kStripes, V(0.35, 0.25, 0.16), V(0.22, 0.15, 0.09), 0.6, 12, 0.30),
      Builtin("foliage", P::kNoise, V(0.25, 0.50, 0.18), V(0.08, 0.25, 0.06), 1.5, 8, 0.40),
      Builtin("facade", P::kFacade, V(0.78, 0.74, 0.66), V(0.20, 0.26, 0.33), 6.0, 2, 0.12),
      Builtin("facade_glass", P::kFacade, V(0.55, 0.58, 0.62), V(0.15, 0.22, 0.30), 4.0, 2, 0.10),
      Builtin("metal", P::kStripes, V(0.72, 0.74, 0.76), V(0.60, 0.62, 0.64), 0.5, 16, 0.08),
      Builtin("glass", P::kFlat, V(0.55, 0.70, 0.80), V(0.55, 0.70, 0.80), 1.0, 1, 0.03),
      Builtin("car_paint", P::kNoise, V(0.75, 0.75, 0.78), V(0.60, 0.60, 0.64), 1.0, 8, 0.05),
      Builtin("cloth", P::kChecker, V(0.30, 0.35, 0.55), V(0.20, 0.22, 0.35), 0.4, 8, 0.15),
      Builtin("floor_tiles", P::kTiles, V(0.80, 0.78, 0.74), V(0.50, 0.48, 0.45), 1.2, 4, 0.10),
      Builtin("whiteboard", P::kNoise, V(0.96, 0.96, 0.96), V(0.85, 0.86, 0.90), 1.0, 8, 0.04),
      Builtin("poster", P::kChecker, V(0.85, 0.30, 0.20), V(0.20, 0.35, 0.75), 0.8, 5, 0.10),
      Builtin("garage_floor", P::kMarkings, V(0.55, 0.55, 0.53), V(0.90, 0.85, 0.30), 8.0, 3, 0.20),
  };
  return kBuiltins;
}

const TextureSpec* FindTexture(const std::vector<TextureSpec>& scene_textures, const std::string& name) {
  for (const TextureSpec& t : scene_textures) {
    if (t.name == name) return &t;
  }
  for (const TextureSpec& t : BuiltinTextures()) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

RgbImage RenderTexture(const TextureSpec& spec) {
  std::string error;
  ROTOLIDAR_CHECK(spec.Validate(&error), error);
  const TileNoise pattern_noise(spec.name + ".pattern"), grain_noise(spec.name + ".grain");
  RgbImage image;
  image.width = image.height = spec.resolution_px;
  image.rgb.resize(static_cast<std::size_t>(3 * image.width * image.height));
  // Fine grain: the noise evaluated at 4x its frequency (still tileable, as 4 is an integer).
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const double u = (x + 0.5) / image.width, v = (y + 0.5) / image.height;
      const double w = PatternWeight(spec, pattern_noise, u, v);
      const double g = 1.0 + spec.grain * (2.0 * grain_noise(4.0 * u, 4.0 * v) - 1.0);
      const Eigen::Vector3d c = ((1.0 - w) * spec.color_a + w * spec.color_b) * g;
      uint8_t* px = &image.rgb[static_cast<std::size_t>(3 * (y * image.width + x))];
      for (int k = 0; k < 3; ++k) px[k] = ToByte(c[k]);
    }
  }
  return image;
}

}  // namespace rotolidar::sim
