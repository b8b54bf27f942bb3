#include "bench/ros/bag_topics.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

std::string Flag(const TopicRole& role) { return std::string("--") + role.role + "-topic"; }

/// "velodyne_msgs/VelodyneScan or sensor_msgs/PointCloud2" for a role with two types.
std::string TypeNames(const TopicRole& role) {
  std::string s = role.type->datatype;
  if (role.alt_type) s += std::string(" or ") + role.alt_type->datatype;
  return s;
}

/// The role's type named `datatype`, or nullptr.
const RosMsgType* TypeOf(const TopicRole& role, const std::string& datatype) {
  if (datatype == role.type->datatype) return role.type;
  if (role.alt_type && datatype == role.alt_type->datatype) return role.alt_type;
  return nullptr;
}

Status CheckType(const BagReader& bag, const TopicRole& role, const BagTopic& t) {
  const RosMsgType* type = TypeOf(role, t.datatype);
  if (type == nullptr)
    return Status::Error(bag.path() + ": topic " + t.topic + " (" + Flag(role) + ") has type " + t.datatype +
                         ", expected " + TypeNames(role));
  if (t.md5 != type->md5 && t.md5 != "*") {
    return Status::Error(bag.path() + ": topic " + t.topic + ": type " + t.datatype + " has md5sum " + t.md5 +
                         ", expected " + type->md5 + " (a different definition of the message)");
  }
  return Status::Ok();
}

Status Choose(const BagReader& bag, const TopicRole& role, const BagTopic& t, std::string* topic,
              const RosMsgType** chosen_type) {
  if (Status s = CheckType(bag, role, t); !s) return s;
  *topic = t.topic;
  if (chosen_type) *chosen_type = TypeOf(role, t.datatype);
  return Status::Ok();
}

}  // namespace

std::string DescribeTopics(const std::vector<BagTopic>& topics) {
  if (topics.empty()) return "no topics";
  std::string s;
  for (const BagTopic& t : topics) {
    if (!s.empty()) s += ", ";
    s += t.topic + " (" + t.datatype + ", " + std::to_string(t.messages) + " messages)";
  }
  return s;
}

Status SelectTopic(const BagReader& bag, const TopicRole& role, const std::string& requested, std::string* topic,
                   const RosMsgType** chosen_type) {
  topic->clear();
  if (chosen_type) *chosen_type = nullptr;
  if (!requested.empty()) {
    std::vector<BagTopic> same_name;
    for (const BagTopic& t : bag.topics())
      if (t.topic == requested) same_name.push_back(t);
    if (same_name.empty())
      return Status::Error(bag.path() + ": no topic " + requested + " (" + Flag(role) + "); the bag has " +
                           DescribeTopics(bag.topics()));
    for (const BagTopic& t : same_name)
      if (TypeOf(role, t.datatype)) return Choose(bag, role, t, topic, chosen_type);
    return CheckType(bag, role, same_name.front());
  }
  std::vector<BagTopic> candidates;
  for (const BagTopic& t : bag.topics())
    if (TypeOf(role, t.datatype)) candidates.push_back(t);
  if (candidates.size() == 1) return Choose(bag, role, candidates.front(), topic, chosen_type);
  if (candidates.size() > 1)
    return Status::Error(bag.path() + ": several " + TypeNames(role) + " topics: " + DescribeTopics(candidates) +
                         "; choose one with " + Flag(role));
  if (!role.required) return Status::Ok();
  return Status::Error(bag.path() + ": no " + TypeNames(role) + " topic for the " + role.role +
                       " stream (a recording needs one); the bag has " + DescribeTopics(bag.topics()));
}

}  // namespace rotolidar::bench::rosmsg
