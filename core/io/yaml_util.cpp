#include "core/io/yaml_util.hpp"

#include <vector>

namespace rotolidar::yaml {

std::string Where(const std::string& file, const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return file + ": ";
  return file + ":" + std::to_string(mark.line + 1) + ": ";
}

std::string KeyName(const std::string& file, const YAML::Node& key, const std::string& context) {
  if (!key.IsScalar())
    throw ParseError(Where(file, key) + context + ": a key must be a plain name, not a " +
                     (key.IsMap() ? "mapping" : key.IsSequence() ? "list" : "null"));
  return key.Scalar();
}

void CheckKeys(const std::string& file, const YAML::Node& node, const std::set<std::string>& allowed,
               const std::string& context) {
  if (!node) return;
  if (!node.IsMap()) throw ParseError(Where(file, node) + context + ": expected a mapping");
  for (const auto& kv : node) {
    const std::string key = KeyName(file, kv.first, context);
    if (!allowed.count(key))
      throw ParseError(Where(file, kv.first) + "unknown key '" + key + "' in " + context);
  }
}

void GetPose(const std::string& file, const YAML::Node& node, const std::string& key, Pose3* pose) {
  if (const YAML::Node p = node[key]) ReadPose(file, p, key, pose);
}

void ReadPose(const std::string& file, const YAML::Node& p, const std::string& field, Pose3* pose) {
  CheckKeys(file, p, {"translation_m", "rotation_wxyz"}, field);
  std::vector<double> t{0, 0, 0}, q{1, 0, 0, 0};
  Get(file, p, "translation_m", &t);
  Get(file, p, "rotation_wxyz", &q);
  if (t.size() != 3) throw ParseError(Where(file, p) + field + ".translation_m: expected 3 numbers");
  if (q.size() != 4) throw ParseError(Where(file, p) + field + ".rotation_wxyz: expected 4 numbers");
  const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
  if (std::abs(quat.norm() - 1.0) > 1e-3)
    throw ParseError(Where(file, p) + field + ".rotation_wxyz: not a unit quaternion");
  *pose = MakePose({t[0], t[1], t[2]}, quat);
}

void EmitPose(YAML::Emitter& out, const std::string& key, const Pose3& pose) {
  out << YAML::Key << key << YAML::Value;
  EmitPoseValue(out, pose);
}

void EmitPoseValue(YAML::Emitter& out, const Pose3& pose) {
  const Eigen::Quaterniond q(pose.linear());
  const Eigen::Vector3d t = pose.translation();
  out << YAML::BeginMap;
  out << YAML::Key << "translation_m" << YAML::Value << YAML::Flow << std::vector<double>{t.x(), t.y(), t.z()};
  out << YAML::Key << "rotation_wxyz" << YAML::Value << YAML::Flow
      << std::vector<double>{q.w(), q.x(), q.y(), q.z()};
  out << YAML::EndMap;
}

YAML::Node LoadFile(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ParseError(path + ": cannot open file");
  } catch (const YAML::ParserException& e) {
    throw ParseError(path + ":" + std::to_string(e.mark.line + 1) + ": YAML syntax error: " + e.msg);
  }
}

}  // namespace rotolidar::yaml
