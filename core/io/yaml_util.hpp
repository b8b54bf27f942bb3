#pragma once
// Helpers for parsing YAML at the edges: strict key checking and messages that name file:line and the key. The
// field-list idiom every config uses (core/io/yaml_fields.hpp) is built on them. Only .cpp files at the YAML
// edges (core/io, sim's parsers, bench) include this: yaml-cpp stays out of the estimator's headers.
#include <cmath>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/types/geometry.hpp"
#include "core/util/status.hpp"

namespace rotolidar::yaml {

/// Thrown inside parsers and caught at their boundary, where it becomes a Status. Never escapes core/.
struct ParseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// "file:line: " for a node (yaml-cpp lines are 0-based; we print 1-based).
std::string Where(const std::string& file, const YAML::Node& node);

/// A mapping key as text; a key that is itself a mapping or a list (`{a: 1}: x`, legal YAML) throws ParseError
/// naming its line and `context`.
std::string KeyName(const std::string& file, const YAML::Node& key, const std::string& context);

/// Fails on any key of `node` not in `allowed`, naming the key and its line.
void CheckKeys(const std::string& file, const YAML::Node& node, const std::set<std::string>& allowed,
               const std::string& context);

/// Reads `node` (present) into *value; a wrong type names file:line and `field`.
template <typename T>
void ReadAs(const std::string& file, const YAML::Node& node, const std::string& field, T* value) {
  [[maybe_unused]] const T before = *value;  // the field's default
  try {
    *value = node.as<T>();
  } catch (const YAML::Exception&) {
    throw ParseError(Where(file, node) + "field '" + field + "': cannot read value '" +
                     (node.IsScalar() ? node.Scalar() : std::string("<non-scalar>")) + "'");
  }
  // YAML spells NaN and infinity (.nan, .inf). NaN is never a value; an infinity only where the field's default
  // is that same infinity (it means "never", e.g. a motor profile's stop_at_s).
  auto finite = [&](double x, bool infinity_allowed) {
    if (std::isnan(x) || (std::isinf(x) && !infinity_allowed))
      throw ParseError(Where(file, node) + "field '" + field + "': not a finite number");
  };
  if constexpr (std::is_floating_point_v<T>) finite(*value, std::isinf(before) && before == *value);
  if constexpr (std::is_same_v<T, std::vector<double>>)
    for (double x : *value) finite(x, false);
}

/// Reads node[key] into *value when present (keeps the default otherwise); wrong types name the key and line.
template <typename T>
void Get(const std::string& file, const YAML::Node& node, const std::string& key, T* value) {
  if (const YAML::Node child = node[key]) ReadAs(file, child, key, value);
}

/// Reads a pose {translation_m: [x,y,z], rotation_wxyz: [w,x,y,z]} (either key optional) from node[key].
void GetPose(const std::string& file, const YAML::Node& node, const std::string& key, Pose3* pose);
/// The same from the pose's own mapping `p`; messages name `field`.
void ReadPose(const std::string& file, const YAML::Node& p, const std::string& field, Pose3* pose);

/// Emits a pose in the same layout, as key: mapping.
void EmitPose(YAML::Emitter& out, const std::string& key, const Pose3& pose);
/// Emits only the pose's mapping (the caller wrote the key).
void EmitPoseValue(YAML::Emitter& out, const Pose3& pose);

/// Loads a YAML file; parse errors name file:line.
YAML::Node LoadFile(const std::string& path);

}  // namespace rotolidar::yaml
