// YAML I/O of CameraConfig (declared in sim/camera/camera_model.hpp): the `camera:` section of a sim config.
#include <string>

#include "core/io/yaml_util.hpp"
#include "sim/camera/camera_model.hpp"

namespace rotolidar::sim {

void ParseCameraConfig(const std::string& file, const YAML::Node& node, CameraConfig* config) {
  using yaml::Get;
  if (!node) return;
  if (!node.IsMap()) throw yaml::ParseError(yaml::Where(file, node) + "camera: expected a mapping");
  yaml::CheckKeys(file, node,
                  {"enabled", "rate_hz", "width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1",
                   "p2", "exposure_s", "readout_s", "quantum_rate_e_per_s", "full_well_e", "read_noise_e", "gain",
                   "gamma", "renderer", "motion_blur", "blur_subframes", "threads", "shadows", "max_range_m"},
                  "camera");
  CameraConfig c = *config;
  Get(file, node, "enabled", &c.enabled);
  Get(file, node, "rate_hz", &c.rate_hz);
  Get(file, node, "width_px", &c.width_px);
  Get(file, node, "height_px", &c.height_px);
  Get(file, node, "fx_px", &c.fx_px);
  Get(file, node, "fy_px", &c.fy_px);
  Get(file, node, "cx_px", &c.cx_px);
  Get(file, node, "cy_px", &c.cy_px);
  Get(file, node, "k1", &c.k1);
  Get(file, node, "k2", &c.k2);
  Get(file, node, "p1", &c.p1);
  Get(file, node, "p2", &c.p2);
  Get(file, node, "exposure_s", &c.exposure_s);
  Get(file, node, "readout_s", &c.readout_s);
  Get(file, node, "quantum_rate_e_per_s", &c.quantum_rate_e_per_s);
  Get(file, node, "full_well_e", &c.full_well_e);
  Get(file, node, "read_noise_e", &c.read_noise_e);
  Get(file, node, "gain", &c.gain);
  Get(file, node, "gamma", &c.gamma);
  Get(file, node, "blur_subframes", &c.blur_subframes);
  Get(file, node, "threads", &c.threads);
  Get(file, node, "shadows", &c.shadows);
  Get(file, node, "max_range_m", &c.max_range_m);
  if (node["renderer"]) {
    std::string name;
    Get(file, node, "renderer", &name);
    if (!ParseCameraRendererKind(name, &c.renderer))
      throw yaml::ParseError(yaml::Where(file, node["renderer"]) + "camera.renderer: embree or osmesa, got '" + name +
                             "'");
  }
  if (node["motion_blur"]) {
    std::string name;
    Get(file, node, "motion_blur", &name);
    if (!ParseMotionBlurKind(name, &c.motion_blur))
      throw yaml::ParseError(yaml::Where(file, node["motion_blur"]) +
                             "camera.motion_blur: none, velocity or subframes, got '" + name + "'");
  }
  std::string why;
  if (!c.Validate(&why)) throw yaml::ParseError(yaml::Where(file, node) + why);
  *config = c;
}

void EmitCameraConfig(YAML::Emitter& out, const CameraConfig& c) {
  out << YAML::BeginMap;
  out << YAML::Key << "enabled" << YAML::Value << c.enabled;
  out << YAML::Key << "rate_hz" << YAML::Value << c.rate_hz;
  out << YAML::Key << "width_px" << YAML::Value << c.width_px;
  out << YAML::Key << "height_px" << YAML::Value << c.height_px;
  const std::pair<const char*, double> lens[] = {{"fx_px", c.fx_px}, {"fy_px", c.fy_px}, {"cx_px", c.cx_px},
                                                 {"cy_px", c.cy_px}, {"k1", c.k1},       {"k2", c.k2},
                                                 {"p1", c.p1},       {"p2", c.p2},       {"exposure_s", c.exposure_s},
                                                 {"readout_s", c.readout_s},
                                                 {"quantum_rate_e_per_s", c.quantum_rate_e_per_s},
                                                 {"full_well_e", c.full_well_e},
                                                 {"read_noise_e", c.read_noise_e},
                                                 {"gain", c.gain},
                                                 {"gamma", c.gamma}};
  for (const auto& [key, value] : lens) out << YAML::Key << key << YAML::Value << value;
  out << YAML::Key << "renderer" << YAML::Value << CameraRendererName(c.renderer);
  out << YAML::Key << "motion_blur" << YAML::Value << MotionBlurName(c.motion_blur);
  out << YAML::Key << "blur_subframes" << YAML::Value << c.blur_subframes;
  out << YAML::Key << "threads" << YAML::Value << c.threads;
  out << YAML::Key << "shadows" << YAML::Value << c.shadows;
  out << YAML::Key << "max_range_m" << YAML::Value << c.max_range_m;
  out << YAML::EndMap;
}

}  // namespace rotolidar::sim
