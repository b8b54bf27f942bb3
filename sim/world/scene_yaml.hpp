#pragma once
// Internal to sim/world's scene loader (scene.cpp, scene_dynamic.cpp): strict YAML reading helpers whose errors
// are yaml::ParseError "<file>:<line>: <what>" naming the key. Include only from .cpp files (yaml-cpp is a
// private dependency of rotolidar::sim).
#include <set>
#include <string>

#include <yaml-cpp/yaml.h>
#include <Eigen/Core>

#include "core/io/yaml_util.hpp"

namespace rotolidar::sim {

class SceneYaml {
 public:
  explicit SceneYaml(std::string path) : path_(std::move(path)) {}
  const std::string& path() const { return path_; }

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& what) const {
    throw yaml::ParseError(yaml::Where(path_, at) + what);
  }

  /// Every key of `map` must be in `allowed` (a non-mapping is an error too).
  void CheckKeys(const YAML::Node& map, const std::set<std::string>& allowed, const std::string& context) const {
    if (!map.IsMap()) Fail(map, context + ": expected a mapping");
    yaml::CheckKeys(path_, map, allowed, context);
  }

  template <typename T>
  T Get(const YAML::Node& map, const std::string& key, const std::string& context) const {
    const YAML::Node node = map[key];
    if (!node) Fail(map, "missing key '" + key + "' in " + context);
    return As<T>(node, key, context);
  }

  template <typename T>
  T GetOr(const YAML::Node& map, const std::string& key, const T& fallback, const std::string& context) const {
    const YAML::Node node = map[key];
    return node ? As<T>(node, key, context) : fallback;
  }

  /// A list of exactly n numbers (n <= 3; missing trailing entries are 0).
  Eigen::Vector3d Vec(const YAML::Node& map, const std::string& key, int n, const std::string& context) const {
    const YAML::Node node = map[key];
    if (!node) Fail(map, "missing key '" + key + "' in " + context);
    return VecNode(node, key, n, context);
  }

  Eigen::Vector3d VecNode(const YAML::Node& node, const std::string& key, int n, const std::string& context) const {
    if (!node.IsSequence() || static_cast<int>(node.size()) != n) {
      Fail(node, "'" + key + "' in " + context + " must be a list of " + std::to_string(n) + " numbers");
    }
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) v[i] = As<double>(node[i], key, context);
    if (!v.allFinite()) Fail(node, "'" + key + "' in " + context + " must be finite");
    return v;
  }

  /// An RGB colour [r, g, b] with entries in [0, 1].
  Eigen::Vector3d Color(const YAML::Node& map, const std::string& key, const std::string& context) const {
    const Eigen::Vector3d c = Vec(map, key, 3, context);
    if (!(c.minCoeff() >= 0.0 && c.maxCoeff() <= 1.0)) {
      Fail(map[key], "'" + key + "' in " + context + " must have entries in [0, 1]");
    }
    return c;
  }

  template <typename T>
  T As(const YAML::Node& node, const std::string& key, const std::string& context) const {
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      Fail(node, "bad value for '" + key + "' in " + context);
    }
  }

 private:
  std::string path_;
};

}  // namespace rotolidar::sim
