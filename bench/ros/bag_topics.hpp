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
  bool required;                         ///< false: no topic of the type is fine (returns "")
  const RosMsgType* alt_type = nullptr;  ///< a second accepted type (lidar: sensor_msgs/PointCloud2), or none
};

/// Picks the topic for `role`: `requested` when given (it must exist with one of the role's types and that type's
/// md5sum), else the only topic of the role's types. Errors name the bag and list the candidates ("several ...
/// topics: /a (12 messages), /b (3 messages); choose one with --imu-topic") or every topic in the bag when there
/// is none. *chosen_type (when not null) is set to the type of the chosen topic (nullptr when none was chosen).
Status SelectTopic(const BagReader& bag, const TopicRole& role, const std::string& requested, std::string* topic,
                   const RosMsgType** chosen_type = nullptr);

/// "/a (sensor_msgs/Imu, 12 messages), /b (...)" or "no topics".
std::string DescribeTopics(const std::vector<BagTopic>& topics);

}  // namespace rotolidar::bench::rosmsg
