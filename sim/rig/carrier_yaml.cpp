// CarrierConfig: type words, validation and YAML I/O (declared in sim/rig/carrier_paths.hpp). The YAML uses the
// project's one idiom (core/io/yaml_fields.hpp): the field lists below drive parse and emit.
#include <cmath>
#include <sstream>
#include <utility>

#include "core/io/yaml_fields.hpp"
#include "core/util/validation.hpp"
#include "sim/rig/carrier_paths.hpp"

namespace rotolidar::sim {

namespace {

bool InRange(std::string* error, const std::string& field, double v, double lo, double hi) {
  if (std::isfinite(v) && v >= lo && v <= hi) return true;
  std::ostringstream os;
  os << field << " must be finite and in [" << lo << ", " << hi << "], got " << v;
  return FailValidation(error, os.str());
}

bool ValidWaypoints(std::string* error, const std::string& section, const std::vector<Waypoint2d>& w,
                    bool closed_loop, int laps) {
  if (w.size() < 2)
    return FailValidation(error, section + ".waypoints: need at least 2, got " + std::to_string(w.size()));
  for (size_t i = 0; i < w.size(); ++i) {
    const std::string name = section + ".waypoints[" + std::to_string(i) + "]";
    if (!std::isfinite(w[i].x_m) || !std::isfinite(w[i].y_m))
      return FailValidation(error, name + ": x_m/y_m not finite");
    if (!InRange(error, name + ".dwell_s", w[i].dwell_s, 0.0, 1e5)) return false;
    const Waypoint2d& prev = i > 0 ? w[i - 1] : w.back();
    if ((i > 0 || closed_loop) && std::hypot(w[i].x_m - prev.x_m, w[i].y_m - prev.y_m) < 0.05)
      return FailValidation(error,
                            name + " is closer than 0.05 m to the waypoint before it (the heading is undefined)");
  }
  if (laps < 1 || laps > 10000) return FailValidation(error, section + ".laps must be in [1, 10000]");
  if (laps > 1 && !closed_loop) return FailValidation(error, section + ".laps > 1 needs closed_loop: true");
  return true;
}

/// A waypoint list [[x_m, y_m], [x_m, y_m, dwell_s], ...]; messages name the item's line and index.
void ReadWaypoints(const yaml::Section& at, const YAML::Node& list, std::vector<Waypoint2d>* out) {
  if (!list.IsSequence()) throw yaml::ParseError(yaml::Where(at.file, list) + at.path + ": expected a list");
  std::vector<Waypoint2d> points;
  for (size_t i = 0; i < list.size(); ++i) {
    const YAML::Node item = list[i];
    std::vector<double> v;
    try {
      v = item.as<std::vector<double>>();
    } catch (const YAML::Exception&) {
      v.clear();
    }
    if (v.size() != 2 && v.size() != 3)
      throw yaml::ParseError(yaml::Where(at.file, item) + at.path + "[" + std::to_string(i) +
                             "]: expected [x_m, y_m] or [x_m, y_m, dwell_s]");
    points.push_back({v[0], v[1], v.size() == 3 ? v[2] : 0.0});
  }
  *out = std::move(points);
}

void EmitWaypoints(YAML::Emitter& out, const std::vector<Waypoint2d>& waypoints) {
  out << YAML::BeginSeq;
  for (const Waypoint2d& w : waypoints) out << YAML::Flow << std::vector<double>{w.x_m, w.y_m, w.dwell_s};
  out << YAML::EndSeq;
}

auto Waypoints(std::vector<Waypoint2d>* w) { return yaml::Custom(w, ReadWaypoints, EmitWaypoints); }

}  // namespace

// ---- the field lists (in the structs' namespace, so the generic visitors find them) ----

template <class V>
void Visit(V& v, ScriptedBaseMotionConfig& c) {
  v("center_x_m", &c.center_x_m), v("center_y_m", &c.center_y_m), v("radius_x_m", &c.radius_x_m);
  v("radius_y_m", &c.radius_y_m), v("shape_harmonic_m", &c.shape_harmonic_m), v("height_m", &c.height_m);
  v("loop_period_s", &c.loop_period_s), v("phase0_rad", &c.phase0_rad);
  v("bounce_amplitude_m", &c.bounce_amplitude_m), v("bounce_hz", &c.bounce_hz);
  v("roll_amplitude_rad", &c.roll_amplitude_rad), v("roll_hz", &c.roll_hz);
  v("pitch_amplitude_rad", &c.pitch_amplitude_rad), v("pitch_hz", &c.pitch_hz), v("duration_s", &c.duration_s);
  v("room_min_x_m", &c.room_min_x_m), v("room_max_x_m", &c.room_max_x_m), v("room_min_y_m", &c.room_min_y_m);
  v("room_max_y_m", &c.room_max_y_m), v("margin_m", &c.margin_m), v("min_speed_mps", &c.min_speed_mps);
  v("max_speed_mps", &c.max_speed_mps);
}

template <class V>
void Visit(V& v, HandheldWalkConfig& c) {
  v("waypoints", Waypoints(&c.waypoints)), v("closed_loop", &c.closed_loop), v("laps", &c.laps);
  v("height_m", &c.height_m), v("speed_mps", &c.speed_mps), v("smoothing_s", &c.smoothing_s);
  v("step_hz", &c.step_hz), v("bounce_amplitude_m", &c.bounce_amplitude_m);
  v("sway_amplitude_m", &c.sway_amplitude_m), v("roll_amplitude_rad", &c.roll_amplitude_rad);
  v("pitch_amplitude_rad", &c.pitch_amplitude_rad);
}

template <class V>
void Visit(V& v, WheeledConfig& c) {
  v("waypoints", Waypoints(&c.waypoints)), v("closed_loop", &c.closed_loop), v("laps", &c.laps);
  v("height_m", &c.height_m), v("speed_mps", &c.speed_mps), v("smoothing_s", &c.smoothing_s);
}

/// Inline waypoints are written only without a waypoints file (which the sim reads instead).
template <class V>
void Visit(V& v, CarConfig& c) {
  v("waypoints_file", yaml::Path(&c.waypoints_file));
  v("waypoints", yaml::EmitIf(c.waypoints_file.empty(), Waypoints(&c.waypoints)));
  v("height_m", &c.height_m), v("cruise_speed_mps", &c.cruise_speed_mps);
  v("max_lateral_accel_mps2", &c.max_lateral_accel_mps2), v("max_accel_mps2", &c.max_accel_mps2);
  v("max_decel_mps2", &c.max_decel_mps2), v("smoothing_s", &c.smoothing_s);
}

template <class V>
void Visit(V& v, KittiPathConfig& c) {
  v("poses_file", yaml::Path(&c.poses_file)), v("times_file", yaml::Path(&c.times_file));
  v("rate_hz", &c.rate_hz), v("height_m", &c.height_m), v("smoothing_s", &c.smoothing_s);
  v("start_x_m", &c.start_x_m), v("start_y_m", &c.start_y_m), v("start_yaw_rad", &c.start_yaw_rad);
}

/// Every section is read when present; only the active type's is written.
template <class V>
void Visit(V& v, CarrierConfig& c) {
  v("type", &c.type);
  v("scripted_loop", yaml::EmitIf(c.type == CarrierType::kScriptedLoop, &c.scripted_loop));
  v("handheld", yaml::EmitIf(c.type == CarrierType::kHandheld, &c.handheld));
  v("wheeled", yaml::EmitIf(c.type == CarrierType::kWheeled, &c.wheeled));
  v("car", yaml::EmitIf(c.type == CarrierType::kCar, &c.car));
  v("kitti", yaml::EmitIf(c.type == CarrierType::kKitti, &c.kitti));
}

const std::vector<std::pair<const char*, CarrierType>>& EnumWords(CarrierType*) {
  static const std::vector<std::pair<const char*, CarrierType>> words{{"scripted_loop", CarrierType::kScriptedLoop},
                                                                      {"handheld", CarrierType::kHandheld},
                                                                      {"wheeled", CarrierType::kWheeled},
                                                                      {"car", CarrierType::kCar},
                                                                      {"kitti", CarrierType::kKitti}};
  return words;
}

const char* CarrierTypeName(CarrierType type) { return yaml::EnumWord(type); }

bool CarrierTypeFromName(const std::string& name, CarrierType* type) { return yaml::EnumFromWord(name, type); }

bool HandheldWalkConfig::Validate(std::string* error) const {
  return ValidWaypoints(error, "handheld", waypoints, closed_loop, laps) &&
         InRange(error, "handheld.height_m", height_m, 0.2, 3.0) &&
         InRange(error, "handheld.speed_mps", speed_mps, 0.2, 2.5) &&
         InRange(error, "handheld.smoothing_s", smoothing_s, 0.2, 20.0) &&
         InRange(error, "handheld.step_hz", step_hz, 0.5, 4.0) &&
         InRange(error, "handheld.bounce_amplitude_m", bounce_amplitude_m, 0.0, 0.1) &&
         InRange(error, "handheld.sway_amplitude_m", sway_amplitude_m, 0.0, 0.1) &&
         InRange(error, "handheld.roll_amplitude_rad", roll_amplitude_rad, 0.0, 0.3) &&
         InRange(error, "handheld.pitch_amplitude_rad", pitch_amplitude_rad, 0.0, 0.3);
}

bool WheeledConfig::Validate(std::string* error) const {
  return ValidWaypoints(error, "wheeled", waypoints, closed_loop, laps) &&
         InRange(error, "wheeled.height_m", height_m, 0.0, 3.0) &&
         InRange(error, "wheeled.speed_mps", speed_mps, 0.05, 5.0) &&
         InRange(error, "wheeled.smoothing_s", smoothing_s, 0.2, 30.0);
}

bool CarConfig::Validate(std::string* error) const {
  if (waypoints_file.empty() && waypoints.size() < 2)
    return FailValidation(
        error, "car.waypoints_file: required, or car.waypoints with >= 2 points (or a scene with a car default path)");
  return InRange(error, "car.height_m", height_m, 0.0, 5.0) &&
         InRange(error, "car.cruise_speed_mps", cruise_speed_mps, 0.5, 70.0) &&
         InRange(error, "car.max_lateral_accel_mps2", max_lateral_accel_mps2, 0.1, 15.0) &&
         InRange(error, "car.max_accel_mps2", max_accel_mps2, 0.1, 10.0) &&
         InRange(error, "car.max_decel_mps2", max_decel_mps2, 0.1, 15.0) &&
         InRange(error, "car.smoothing_s", smoothing_s, 0.1, 10.0);
}

bool KittiPathConfig::Validate(std::string* error) const {
  if (poses_file.empty()) return FailValidation(error, "kitti.poses_file: required");
  return InRange(error, "kitti.rate_hz", rate_hz, 1e-3, 1e4) && InRange(error, "kitti.height_m", height_m, -100, 100) &&
         InRange(error, "kitti.smoothing_s", smoothing_s, 0.0, 10.0) &&
         InRange(error, "kitti.start_x_m", start_x_m, -1e6, 1e6) &&
         InRange(error, "kitti.start_y_m", start_y_m, -1e6, 1e6) &&
         InRange(error, "kitti.start_yaw_rad", start_yaw_rad, -10, 10);
}

bool UsesSceneDefaultPath(const CarrierConfig& c) {
  return (c.type == CarrierType::kHandheld && c.handheld.waypoints.empty()) ||
         (c.type == CarrierType::kWheeled && c.wheeled.waypoints.empty()) ||
         (c.type == CarrierType::kCar && c.car.waypoints.empty() && c.car.waypoints_file.empty());
}

bool CarrierConfig::Validate(std::string* error) const {
  switch (type) {
    case CarrierType::kScriptedLoop:
      if (scripted_loop.Validate(error)) return true;
      if (error) *error = "scripted_loop: " + *error;
      return false;
    case CarrierType::kHandheld: return handheld.Validate(error);
    case CarrierType::kWheeled: return wheeled.Validate(error);
    case CarrierType::kCar: return car.Validate(error);
    case CarrierType::kKitti: return kitti.Validate(error);
  }
  return FailValidation(error, "carrier.type: unknown");
}

Status ParseCarrierConfig(const std::string& file, const YAML::Node& node, CarrierConfig* config) {
  if (!node) return Status::Ok();
  CarrierConfig c = *config;
  try {
    yaml::Parse(yaml::Section(file, "carrier"), node, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  const YAML::Node active = node[CarrierTypeName(c.type)];
  // Handheld/wheeled/car without waypoints follow the scene's default path; the sim validates them after loading it.
  if (!UsesSceneDefaultPath(c) && !c.Validate(&why))
    return Status::Error(yaml::Where(file, active ? active : node) + "carrier." + why);
  *config = c;
  return Status::Ok();
}

void EmitCarrierConfig(YAML::Emitter& out, const CarrierConfig& c) { yaml::Emit(out, c); }

}  // namespace rotolidar::sim
