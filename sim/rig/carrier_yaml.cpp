// CarrierConfig: type names, validation and YAML I/O (declared in sim/rig/carrier_paths.hpp).
#include <cmath>
#include <filesystem>
#include <sstream>
#include <utility>

#include "core/io/yaml_util.hpp"
#include "sim/rig/carrier_paths.hpp"

namespace rotolidar::sim {
namespace {

constexpr std::pair<CarrierType, const char*> kTypeNames[] = {{CarrierType::kScriptedLoop, "scripted_loop"},
                                                              {CarrierType::kHandheld, "handheld"},
                                                              {CarrierType::kWheeled, "wheeled"},
                                                              {CarrierType::kCar, "car"},
                                                              {CarrierType::kKitti, "kitti"}};

bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

bool InRange(std::string* error, const std::string& field, double v, double lo, double hi) {
  if (std::isfinite(v) && v >= lo && v <= hi) return true;
  std::ostringstream os;
  os << field << " must be finite and in [" << lo << ", " << hi << "], got " << v;
  return Fail(error, os.str());
}

bool ValidWaypoints(std::string* error, const std::string& section, const std::vector<Waypoint2d>& w,
                    bool closed_loop, int laps) {
  if (w.size() < 2) return Fail(error, section + ".waypoints: need at least 2, got " + std::to_string(w.size()));
  for (size_t i = 0; i < w.size(); ++i) {
    const std::string name = section + ".waypoints[" + std::to_string(i) + "]";
    if (!std::isfinite(w[i].x_m) || !std::isfinite(w[i].y_m)) return Fail(error, name + ": x_m/y_m not finite");
    if (!InRange(error, name + ".dwell_s", w[i].dwell_s, 0.0, 1e5)) return false;
    const Waypoint2d& prev = i > 0 ? w[i - 1] : w.back();
    if ((i > 0 || closed_loop) && std::hypot(w[i].x_m - prev.x_m, w[i].y_m - prev.y_m) < 0.05)
      return Fail(error, name + " is closer than 0.05 m to the waypoint before it (the heading is undefined)");
  }
  if (laps < 1 || laps > 10000) return Fail(error, section + ".laps must be in [1, 10000]");
  if (laps > 1 && !closed_loop) return Fail(error, section + ".laps > 1 needs closed_loop: true");
  return true;
}

/// The plain numeric fields of each config, by YAML key (C may be const).
template <class C>
auto Fields(C& c) {
  using P = decltype(&c.height_m);
  if constexpr (std::is_same_v<std::remove_const_t<C>, HandheldWalkConfig>)
    return std::vector<std::pair<const char*, P>>{
        {"height_m", &c.height_m},       {"speed_mps", &c.speed_mps},
        {"smoothing_s", &c.smoothing_s}, {"step_hz", &c.step_hz},
        {"bounce_amplitude_m", &c.bounce_amplitude_m}, {"sway_amplitude_m", &c.sway_amplitude_m},
        {"roll_amplitude_rad", &c.roll_amplitude_rad}, {"pitch_amplitude_rad", &c.pitch_amplitude_rad}};
  else if constexpr (std::is_same_v<std::remove_const_t<C>, WheeledConfig>)
    return std::vector<std::pair<const char*, P>>{
        {"height_m", &c.height_m}, {"speed_mps", &c.speed_mps}, {"smoothing_s", &c.smoothing_s}};
  else if constexpr (std::is_same_v<std::remove_const_t<C>, CarConfig>)
    return std::vector<std::pair<const char*, P>>{{"height_m", &c.height_m},
                                                  {"cruise_speed_mps", &c.cruise_speed_mps},
                                                  {"max_lateral_accel_mps2", &c.max_lateral_accel_mps2},
                                                  {"max_accel_mps2", &c.max_accel_mps2},
                                                  {"max_decel_mps2", &c.max_decel_mps2},
                                                  {"smoothing_s", &c.smoothing_s}};
  else if constexpr (std::is_same_v<std::remove_const_t<C>, KittiPathConfig>)
    return std::vector<std::pair<const char*, P>>{{"rate_hz", &c.rate_hz},     {"height_m", &c.height_m},
                                                  {"smoothing_s", &c.smoothing_s},
                                                  {"start_x_m", &c.start_x_m}, {"start_y_m", &c.start_y_m},
                                                  {"start_yaw_rad", &c.start_yaw_rad}};
  else
    return std::vector<std::pair<const char*, P>>{
        {"center_x_m", &c.center_x_m},   {"center_y_m", &c.center_y_m},     {"radius_x_m", &c.radius_x_m},
        {"radius_y_m", &c.radius_y_m},   {"shape_harmonic_m", &c.shape_harmonic_m},
        {"height_m", &c.height_m},       {"loop_period_s", &c.loop_period_s}, {"phase0_rad", &c.phase0_rad},
        {"bounce_amplitude_m", &c.bounce_amplitude_m}, {"bounce_hz", &c.bounce_hz},
        {"roll_amplitude_rad", &c.roll_amplitude_rad}, {"roll_hz", &c.roll_hz},
        {"pitch_amplitude_rad", &c.pitch_amplitude_rad}, {"pitch_hz", &c.pitch_hz},
        {"duration_s", &c.duration_s},   {"room_min_x_m", &c.room_min_x_m}, {"room_max_x_m", &c.room_max_x_m},
        {"room_min_y_m", &c.room_min_y_m}, {"room_max_y_m", &c.room_max_y_m}, {"margin_m", &c.margin_m},
        {"min_speed_mps", &c.min_speed_mps}, {"max_speed_mps", &c.max_speed_mps}};
}

std::string ResolvePath(const std::string& yaml_file, const std::string& path) {
  namespace fs = std::filesystem;
  if (path.empty() || fs::path(path).is_absolute()) return path;
  const fs::path dir = fs::path(yaml_file).parent_path();
  return dir.empty() ? path : (dir / path).lexically_normal().string();
}

void ParseWaypoints(const std::string& file, const YAML::Node& section, const std::string& name,
                    std::vector<Waypoint2d>* out) {
  const YAML::Node list = section["waypoints"];
  if (!list) return;
  if (!list.IsSequence()) throw yaml::ParseError(yaml::Where(file, list) + name + ".waypoints: expected a list");
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
      throw yaml::ParseError(yaml::Where(file, item) + name + ".waypoints[" + std::to_string(i) +
                             "]: expected [x_m, y_m] or [x_m, y_m, dwell_s]");
    points.push_back({v[0], v[1], v.size() == 3 ? v[2] : 0.0});
  }
  *out = std::move(points);
}

template <class C>
void ParseSection(const std::string& file, const YAML::Node& node, const std::string& name, C* c) {
  const YAML::Node n = node[name];
  if (!n) return;
  std::set<std::string> keys;
  for (const auto& [key, ptr] : Fields(*c)) keys.insert(key), yaml::Get(file, n, key, ptr);
  if constexpr (std::is_same_v<C, HandheldWalkConfig> || std::is_same_v<C, WheeledConfig>) {
    keys.insert({"waypoints", "closed_loop", "laps"});
    ParseWaypoints(file, n, name, &c->waypoints);
    yaml::Get(file, n, "closed_loop", &c->closed_loop);
    yaml::Get(file, n, "laps", &c->laps);
  } else if constexpr (std::is_same_v<C, CarConfig>) {
    keys.insert({"waypoints_file", "waypoints"});
    yaml::Get(file, n, "waypoints_file", &c->waypoints_file);
    ParseWaypoints(file, n, name, &c->waypoints);
    c->waypoints_file = ResolvePath(file, c->waypoints_file);
  } else if constexpr (std::is_same_v<C, KittiPathConfig>) {
    keys.insert({"poses_file", "times_file"});
    yaml::Get(file, n, "poses_file", &c->poses_file);
    yaml::Get(file, n, "times_file", &c->times_file);
    c->poses_file = ResolvePath(file, c->poses_file);
    c->times_file = ResolvePath(file, c->times_file);
  }
  yaml::CheckKeys(file, n, keys, "carrier." + name);
}

void EmitWaypoints(YAML::Emitter& out, const std::vector<Waypoint2d>& waypoints) {
  out << YAML::Key << "waypoints" << YAML::Value << YAML::BeginSeq;
  for (const Waypoint2d& w : waypoints) out << YAML::Flow << std::vector<double>{w.x_m, w.y_m, w.dwell_s};
  out << YAML::EndSeq;
}

template <class C>
void EmitSection(YAML::Emitter& out, const std::string& name, const C& c) {
  out << YAML::Key << name << YAML::Value << YAML::BeginMap;
  if constexpr (std::is_same_v<C, HandheldWalkConfig> || std::is_same_v<C, WheeledConfig>) {
    EmitWaypoints(out, c.waypoints);
    out << YAML::Key << "closed_loop" << YAML::Value << c.closed_loop << YAML::Key << "laps" << YAML::Value << c.laps;
  } else if constexpr (std::is_same_v<C, CarConfig>) {
    out << YAML::Key << "waypoints_file" << YAML::Value << c.waypoints_file;
    if (c.waypoints_file.empty()) EmitWaypoints(out, c.waypoints);
  } else if constexpr (std::is_same_v<C, KittiPathConfig>) {
    out << YAML::Key << "poses_file" << YAML::Value << c.poses_file << YAML::Key << "times_file" << YAML::Value
        << c.times_file;
  }
  for (const auto& [key, ptr] : Fields(c)) out << YAML::Key << key << YAML::Value << *ptr;
  out << YAML::EndMap;
}

}  // namespace

const char* CarrierTypeName(CarrierType type) {
  for (const auto& [t, name] : kTypeNames)
    if (t == type) return name;
  return "unknown";
}

bool CarrierTypeFromName(const std::string& name, CarrierType* type) {
  for (const auto& [t, n] : kTypeNames)
    if (name == n) return *type = t, true;
  return false;
}

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
    return Fail(error, "car.waypoints_file: required, or car.waypoints with >= 2 points (or a scene with a car default path)");
  return InRange(error, "car.height_m", height_m, 0.0, 5.0) &&
         InRange(error, "car.cruise_speed_mps", cruise_speed_mps, 0.5, 70.0) &&
         InRange(error, "car.max_lateral_accel_mps2", max_lateral_accel_mps2, 0.1, 15.0) &&
         InRange(error, "car.max_accel_mps2", max_accel_mps2, 0.1, 10.0) &&
         InRange(error, "car.max_decel_mps2", max_decel_mps2, 0.1, 15.0) &&
         InRange(error, "car.smoothing_s", smoothing_s, 0.1, 10.0);
}

bool KittiPathConfig::Validate(std::string* error) const {
  if (poses_file.empty()) return Fail(error, "kitti.poses_file: required");
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
  return Fail(error, "carrier.type: unknown");
}

void ParseCarrierConfig(const std::string& file, const YAML::Node& node, CarrierConfig* config) {
  if (!node) return;
  yaml::CheckKeys(file, node, {"type", "scripted_loop", "handheld", "wheeled", "car", "kitti"}, "carrier");
  CarrierConfig c = *config;
  if (const YAML::Node type = node["type"]) {
    std::string name;
    yaml::Get(file, node, "type", &name);
    if (!CarrierTypeFromName(name, &c.type))
      throw yaml::ParseError(yaml::Where(file, type) + "carrier.type: unknown '" + name +
                             "' (scripted_loop, handheld, wheeled, car, kitti)");
  }
  ParseSection(file, node, "scripted_loop", &c.scripted_loop);
  ParseSection(file, node, "handheld", &c.handheld);
  ParseSection(file, node, "wheeled", &c.wheeled);
  ParseSection(file, node, "car", &c.car);
  ParseSection(file, node, "kitti", &c.kitti);
  std::string why;
  const YAML::Node active = node[CarrierTypeName(c.type)];
  // Handheld/wheeled/car without waypoints follow the scene's default path; the sim validates them after loading it.
  if (!UsesSceneDefaultPath(c) && !c.Validate(&why))
    throw yaml::ParseError(yaml::Where(file, active ? active : node) + "carrier." + why);
  *config = c;
}

void EmitCarrierConfig(YAML::Emitter& out, const CarrierConfig& c) {
  out << YAML::BeginMap << YAML::Key << "type" << YAML::Value << CarrierTypeName(c.type);
  switch (c.type) {
    case CarrierType::kScriptedLoop: EmitSection(out, "scripted_loop", c.scripted_loop); break;
    case CarrierType::kHandheld: EmitSection(out, "handheld", c.handheld); break;
    case CarrierType::kWheeled: EmitSection(out, "wheeled", c.wheeled); break;
    case CarrierType::kCar: EmitSection(out, "car", c.car); break;
    case CarrierType::kKitti: EmitSection(out, "kitti", c.kitti); break;
  }
  out << YAML::EndMap;
}

}  // namespace rotolidar::sim
