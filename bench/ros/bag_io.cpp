// rosbag glue: raw message bodies in and out of librosbag_storage (Debian's ROS 1 bag library).
#include "bench/ros/bag_io.hpp"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <algorithm>
#include <boost/make_shared.hpp>
#include <cstring>
#include <exception>
#include <map>

namespace rotolidar::bench::rosmsg {
namespace {

/// A serialised message with its type, as rosbag::Bag::write needs it (the traits below, like rosbag's own
/// MessageInstance specialisations).
struct RawMessage {
  const RosMsgType* type = nullptr;
  const std::vector<uint8_t>* body = nullptr;
};

}  // namespace
}  // namespace rotolidar::bench::rosmsg

namespace ros::message_traits {
template <>
struct MD5Sum<rotolidar::bench::rosmsg::RawMessage> {
  static const char* value(const rotolidar::bench::rosmsg::RawMessage& m) { return m.type->md5; }
};
template <>
struct DataType<rotolidar::bench::rosmsg::RawMessage> {
  static const char* value(const rotolidar::bench::rosmsg::RawMessage& m) { return m.type->datatype; }
};
template <>
struct Definition<rotolidar::bench::rosmsg::RawMessage> {
  static const char* value(const rotolidar::bench::rosmsg::RawMessage& m) { return m.type->definition.c_str(); }
};
}  // namespace ros::message_traits

namespace ros::serialization {
template <>
struct Serializer<rotolidar::bench::rosmsg::RawMessage> {
  template <typename Stream>
  static void write(Stream& stream, const rotolidar::bench::rosmsg::RawMessage& m) {
    if (!m.body->empty())
      std::memcpy(stream.advance(static_cast<uint32_t>(m.body->size())), m.body->data(), m.body->size());
  }
  static uint32_t serializedLength(const rotolidar::bench::rosmsg::RawMessage& m) {
    return static_cast<uint32_t>(m.body->size());
  }
};
}  // namespace ros::serialization

namespace rotolidar::bench::rosmsg {

struct BagWriter::Impl {
  rosbag::Bag bag;
  bool open = false;
};

BagWriter::BagWriter() : impl_(std::make_unique<Impl>()) {}
BagWriter::~BagWriter() { (void)Close(); }

Status BagWriter::Open(const std::string& path) {
  path_ = path;
  try {
    impl_->bag.open(path, rosbag::bagmode::Write);
  } catch (const std::exception& e) {
    return Status::Error(path + ": cannot write bag: " + e.what());
  }
  impl_->open = true;
  written_ = 0;
  return Status::Ok();
}

Status BagWriter::Write(const std::string& topic, const RosTime& time, const RosMsgType& type,
                        const std::vector<uint8_t>& body, bool latched) {
  if (!impl_->open) return Status::Error(path_ + ": bag is not open for writing");
  if (time.sec == 0 && time.nsec == 0)
    return Status::Error(path_ + ": topic " + topic + ": record time 0 is not allowed in a bag");
  RawMessage raw{&type, &body};
  try {
    boost::shared_ptr<::ros::M_string> header;
    if (latched) {
      header = boost::make_shared<::ros::M_string>();
      (*header)["callerid"] = "/rotolidar";
      (*header)["topic"] = topic;
      (*header)["type"] = type.datatype;
      (*header)["md5sum"] = type.md5;
      (*header)["message_definition"] = type.definition;
      (*header)["latching"] = "1";
    }
    impl_->bag.write(topic, ::ros::Time(time.sec, time.nsec), raw, header);
  } catch (const std::exception& e) {
    return Status::Error(path_ + ": topic " + topic + ": cannot write message: " + e.what());
  }
  ++written_;
  return Status::Ok();
}

Status BagWriter::Close() {
  if (!impl_ || !impl_->open) return Status::Ok();
  impl_->open = false;
  try {
    impl_->bag.close();
  } catch (const std::exception& e) {
    return Status::Error(path_ + ": cannot finish bag: " + e.what());
  }
  return Status::Ok();
}

struct BagReader::Impl {
  rosbag::Bag bag;
};

BagReader::BagReader() : impl_(std::make_unique<Impl>()) {}
BagReader::~BagReader() = default;

Status BagReader::Open(const std::string& path) {
  path_ = path;
  topics_.clear();
  impl_ = std::make_unique<Impl>();
  try {
    impl_->bag.open(path, rosbag::bagmode::Read);
    rosbag::View view(impl_->bag);
    std::map<std::pair<std::string, std::string>, BagTopic> by_topic;
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      BagTopic& t = by_topic[{c->topic, c->datatype}];
      t.topic = c->topic;
      t.datatype = c->datatype;
      t.md5 = c->md5sum;
    }
    for (auto& [key, t] : by_topic) {  // counted from the index: no message is read
      const std::string topic = t.topic, datatype = t.datatype;
      rosbag::View one(impl_->bag, [topic, datatype](const rosbag::ConnectionInfo* c) {
        return c->topic == topic && c->datatype == datatype;
      });
      t.messages = one.size();
      topics_.push_back(t);
    }
  } catch (const std::exception& e) {
    return Status::Error(path + ": not a readable ROS 1 bag: " + e.what());
  }
  return Status::Ok();
}

Status BagReader::ForEach(const std::vector<std::string>& topics,
                          const std::function<Status(const BagMessage&)>& visit) const {
  std::map<std::string, std::size_t> next_index;
  BagMessage msg;
  try {
    rosbag::View view(impl_->bag, rosbag::TopicQuery(topics));
    for (const rosbag::MessageInstance& m : view) {
      msg.topic = m.getTopic();
      msg.datatype = m.getDataType();
      msg.md5 = m.getMD5Sum();
      msg.time = {m.getTime().sec, m.getTime().nsec};
      msg.index = next_index[msg.topic]++;
      msg.body.resize(m.size());
      ::ros::serialization::OStream stream(msg.body.data(), static_cast<uint32_t>(msg.body.size()));
      m.write(stream);
      if (Status s = visit(msg); !s) return s;
    }
  } catch (const std::exception& e) {
    if (msg.topic.empty()) return Status::Error(path_ + ": cannot read messages: " + e.what());
    return Status::Error(path_ + ": topic " + msg.topic + ", after message " + std::to_string(msg.index) +
                         ": cannot read the next message: " + e.what());
  }
  return Status::Ok();
}

}  // namespace rotolidar::bench::rosmsg
