// YAML I/O of CameraConfig (declared in sim/camera/camera_model.hpp): the `camera:` section of a sim config,
// with the project's one idiom (core/io/yaml_fields.hpp): the field list below drives parse and emit.
#include <string>

#include "core/io/yaml_fields.hpp"
#include "sim/camera/camera_model.hpp"

namespace rotolidar::sim {

template <class V>
void Visit(V& v, CameraConfig& c) {
  v("enabled", &c.enabled), v("rate_hz", &c.rate_hz), v("width_px", &c.width_px), v("height_px", &c.height_px);
  v("fx_px", &c.fx_px), v("fy_px", &c.fy_px), v("cx_px", &c.cx_px), v("cy_px", &c.cy_px);
  v("k1", &c.k1), v("k2", &c.k2), v("p1", &c.p1), v("p2", &c.p2);
  v("exposure_s", &c.exposure_s), v("readout_s", &c.readout_s), v("quantum_rate_e_per_s", &c.quantum_rate_e_per_s);
  v("full_well_e", &c.full_well_e), v("read_noise_e", &c.read_noise_e), v("gain", &c.gain), v("gamma", &c.gamma);
  v("renderer", &c.renderer), v("motion_blur", &c.motion_blur), v("blur_subframes", &c.blur_subframes);
  v("threads", &c.threads), v("shadows", &c.shadows), v("max_range_m", &c.max_range_m);
}

Status ParseCameraConfig(const std::string& file, const YAML::Node& node, CameraConfig* config) {
  if (!node) return Status::Ok();
  CameraConfig c = *config;
  try {
    yaml::Parse(yaml::Section(file, "camera"), node, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(yaml::Where(file, node) + why);
  *config = c;
  return Status::Ok();
}

void EmitCameraConfig(YAML::Emitter& out, const CameraConfig& c) { yaml::Emit(out, c); }

}  // namespace rotolidar::sim
