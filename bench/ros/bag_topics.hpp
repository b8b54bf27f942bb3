#pragma once
// Choosing a bag's topics for the import: by flag or, when the flag is empty, the only topic of the right type.
#include <string>
#include <vector>

#include "bench/ros/bag_io.hpp"

namespace rotolidar::bench::rosmsg {

/// What one input stream of the import needs.
struct TopicRole {
  const char* role;  ///< "lidar", "imu", "image", "encoder" (names the flag: --<role>-topic)
  const RosMsgType* type;
  bool required;  ///< false: no topic of the type is fine (returns "")
};

/// Picks the topic for `role`: `requested` when given (it must exist with the role's type and md5sum), else the
/// only topic of the role's type. Errors name the bag and list the candidates ("several ... topics: /a (12
/// messages), /b (3 messages); choose one with --imu-topic") or every topic in the bag when there is none.
/// A LiDAR topic of type sensor_msgs/PointCloud2 gets its own "not supported yet" error.
Status SelectTopic(const BagReader& bag, const TopicRole& role, const std::string& requested, std::string* topic);

/// "/a (sensor_msgs/Imu, 12 messages), /b (...)" or "no topics".
std::string DescribeTopics(const std::vector<BagTopic>& topics);

}  // namespace rotolidar::bench::rosmsg
