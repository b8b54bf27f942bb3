#pragma once
// ROS 1 bag files through Debian's librosbag_storage, with raw message bodies: the only place rotolidar includes
// rosbag (and its Boost and ROS headers). Every rosbag exception becomes a Status naming the bag; nothing throws
// out of these classes.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench/ros/ros_messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench::rosmsg {

/// One topic of a bag: its type as recorded (type name and md5sum) and its message count.
struct BagTopic {
  std::string topic, datatype, md5;
  std::size_t messages = 0;
};

/// One message as stored: topic, receive time (the bag's record time), type and the serialised body.
struct BagMessage {
  std::string topic, datatype, md5;
  RosTime time;
  std::vector<uint8_t> body;
  std::size_t index = 0;  ///< 0-based index of this message within its topic, in bag time order
};

/// Writes a bag (uncompressed, bag format 2.0). Not thread-safe; Close() (or the destructor) writes the index.
class BagWriter {
 public:
  BagWriter();
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  /// Creates/truncates `path`. Fails naming the file when it cannot be written.
  Status Open(const std::string& path);
  /// Appends one message on `topic` recorded at `time` (must be > 0). `latched`: the connection is marked
  /// "latching" (rosbag play re-sends it to late subscribers, as RViz needs for a map published once).
  Status Write(const std::string& topic, const RosTime& time, const RosMsgType& type, const std::vector<uint8_t>& body,
               bool latched = false);
  template <class Msg>
  Status WriteMsg(const std::string& topic, const RosTime& time, const Msg& msg, bool latched = false) {
    return Write(topic, time, Msg::Type(), Serialize(msg), latched);
  }
  Status Close();
  std::size_t written() const { return written_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  std::size_t written_ = 0;
};

/// Reads a bag's topics and messages.
class BagReader {
 public:
  BagReader();
  ~BagReader();
  BagReader(const BagReader&) = delete;
  BagReader& operator=(const BagReader&) = delete;

  /// Opens and indexes `path`. Fails with "BAG: not a readable ROS 1 bag: <rosbag's reason>" (missing file,
  /// not a bag, truncated or unindexed bag, unknown compression).
  Status Open(const std::string& path);
  /// The topics, sorted by name (a topic recorded with two types appears once per type).
  const std::vector<BagTopic>& topics() const { return topics_; }
  /// Calls `visit` for every message of `topics`, in bag time order; stops at the first error `visit` returns
  /// (or a read error of the bag, naming it) and returns it.
  Status ForEach(const std::vector<std::string>& topics, const std::function<Status(const BagMessage&)>& visit) const;
  const std::string& path() const { return path_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  std::vector<BagTopic> topics_;
};

}  // namespace rotolidar::bench::rosmsg
