#include "bench/ros/bag_topics.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

constexpr const char* kPointCloud2 = "sensor_msgs/PointCloud2";

std::string Flag(const TopicRole& role) { return std::string("--") + role.role + "-topic"; }

Status PointCloudNotSupported(const BagReader& bag, const std::string& topic) {
  return Status::Error(bag.path() + ": topic " + topic +
                       " is a sensor_msgs/PointCloud2: LiDAR import from point "
                       "clouds is not supported yet; it needs velodyne_msgs/VelodyneScan (the raw VLP-16 packets, "
                       "as the velodyne driver records them; docs/ros.md)");
}

Status CheckType(const BagReader& bag, const TopicRole& role, const BagTopic& t) {
  if (t.datatype != role.type->datatype) {
    if (std::string(role.role) == "lidar" && t.datatype == kPointCloud2) return PointCloudNotSupported(bag, t.topic);
    return Status::Error(bag.path() + ": topic " + t.topic + " (" + Flag(role) + ") has type " + t.datatype +
                         ", expected " + role.type->datatype);
  }
  if (t.md5 != role.type->md5 && t.md5 != "*") {
    return Status::Error(bag.path() + ": topic " + t.topic + ": type " + t.datatype + " has md5sum " + t.md5 +
                         ", expected " + role.type->md5 + " (a different definition of the message)");
  }
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

Status SelectTopic(const BagReader& bag, const TopicRole& role, const std::string& requested, std::string* topic) {
  topic->clear();
  if (!requested.empty()) {
    std::vector<BagTopic> same_name;
    for (const BagTopic& t : bag.topics())
      if (t.topic == requested) same_name.push_back(t);
    if (same_name.empty())
      return Status::Error(bag.path() + ": no topic " + requested + " (" + Flag(role) + "); the bag has " +
                           DescribeTopics(bag.topics()));
    for (const BagTopic& t : same_name)
      if (t.datatype == role.type->datatype) {
        if (Status s = CheckType(bag, role, t); !s) return s;
        *topic = t.topic;
        return Status::Ok();
      }
    return CheckType(bag, role, same_name.front());
  }
  std::vector<BagTopic> candidates, clouds;
  for (const BagTopic& t : bag.topics()) {
    if (t.datatype == role.type->datatype) candidates.push_back(t);
    if (t.datatype == kPointCloud2) clouds.push_back(t);
  }
  if (candidates.size() == 1) {
    if (Status s = CheckType(bag, role, candidates.front()); !s) return s;
    *topic = candidates.front().topic;
    return Status::Ok();
  }
  if (candidates.size() > 1)
    return Status::Error(bag.path() + ": several " + role.type->datatype + " topics: " + DescribeTopics(candidates) +
                         "; choose one with " + Flag(role));
  if (!role.required) return Status::Ok();
  if (std::string(role.role) == "lidar" && !clouds.empty()) return PointCloudNotSupported(bag, clouds.front().topic);
  return Status::Error(bag.path() + ": no " + role.type->datatype + " topic for the " + role.role +
                       " stream (a recording needs one); the bag has " + DescribeTopics(bag.topics()));
}

}  // namespace rotolidar::bench::rosmsg
