#include "bench/ros/bag_import.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>

#include "bench/ros/bag_io.hpp"
#include "bench/ros/bag_topics.hpp"
#include "bench/ros/cloud_to_packets.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

enum class Stream { kLidar, kCloud, kImu, kImage, kEncoder };  // kCloud: LiDAR as sensor_msgs/PointCloud2

/// The chosen topics and what each carries.
struct Plan {
  std::map<std::string, Stream> streams;
  std::vector<std::string> topics;
  bool lidar_is_cloud = false;  ///< the LiDAR topic is a sensor_msgs/PointCloud2
};

/// "BAG: topic T, message I: " (every per-message error starts so).
std::string Where(const std::string& bag, const BagMessage& m) {
  return bag + ": topic " + m.topic + ", message " + std::to_string(m.index) + ": ";
}

Status ChooseTopics(const BagReader& bag, const BagImportOptions& o, Plan* plan, BagImportSummary* sum) {
  const TopicRole roles[] = {{"lidar", &VelodyneScanMsg::Type(), true, &PointCloud2Msg::Type()},
                             {"imu", &ImuMsg::Type(), true},
                             {"encoder", &JointStateMsg::Type(), true},
                             {"image", &ImageMsg::Type(), false}};
  const std::string* requested[] = {&o.lidar_topic, &o.imu_topic, &o.encoder_topic, &o.image_topic};
  std::string* chosen[] = {&sum->lidar_topic, &sum->imu_topic, &sum->encoder_topic, &sum->image_topic};
  const Stream streams[] = {Stream::kLidar, Stream::kImu, Stream::kEncoder, Stream::kImage};
  for (int i = 0; i < 4; ++i) {
    if (streams[i] == Stream::kImage && *requested[i] == "none") continue;
    const RosMsgType* type = nullptr;
    if (Status s = SelectTopic(bag, roles[i], *requested[i], chosen[i], &type); !s) return s;
    if (chosen[i]->empty()) continue;
    if (plan->streams.count(*chosen[i]))
      return Status::Error(bag.path() + ": topic " + *chosen[i] + " is chosen for two streams");
    plan->streams[*chosen[i]] = type == &PointCloud2Msg::Type() ? Stream::kCloud : streams[i];
    plan->lidar_is_cloud |= type == &PointCloud2Msg::Type();
    plan->topics.push_back(*chosen[i]);
  }
  return Status::Ok();
}

/// Parses `m` as its stream's message and lowers *min_ns to its earliest stamp (header, each packet's, or a
/// cloud's earliest firing sequence).
Status EarliestStamp(const std::string& bag, const LidarIntrinsics& lidar, Stream stream, const BagMessage& m,
                     int64_t* min_ns) {
  Status s;
  int64_t t = std::numeric_limits<int64_t>::max();
  if (stream == Stream::kLidar) {
    VelodyneScanMsg scan;
    s = Parse(m.body, &scan);
    for (const VelodynePacketMsg& p : scan.packets) t = std::min(t, p.stamp.ToNs());
    if (s && scan.packets.empty()) t = scan.header.stamp.ToNs();
  } else if (stream == Stream::kCloud) {  // the earliest firing sequence (point times may precede the stamp)
    PointCloud2Msg cloud;
    std::vector<CloudPoint> points;
    s = Parse(m.body, &cloud);
    if (s) s = ReadCloudPoints(cloud, &points);
    t = cloud.header.stamp.ToNs() + EarliestSequenceOffsetNs(points, lidar);
  } else if (stream == Stream::kImu) {
    ImuMsg imu;
    s = Parse(m.body, &imu);
    t = imu.header.stamp.ToNs();
  } else if (stream == Stream::kImage) {
    ImageMsg image;
    s = Parse(m.body, &image);
    t = image.header.stamp.ToNs();
  } else {
    JointStateMsg joint;
    s = Parse(m.body, &joint);
    t = joint.header.stamp.ToNs();
  }
  if (!s) return Status::Error(Where(bag, m) + s.message);
  *min_ns = std::min(*min_ns, t);
  return Status::Ok();
}

/// Streams the parsed messages into a RecordingWriter, checking per-topic time order.
class Converter {
 public:
  Converter(std::string bag, const RigCalib& calib, int64_t epoch_ns, RecordingWriter* writer)
      : bag_(std::move(bag)), calib_(calib), epoch_ns_(epoch_ns), writer_(writer), packetizer_(calib.lidar) {}

  Status Convert(Stream stream, const BagMessage& m, BagImportSummary* sum) {
    switch (stream) {
      case Stream::kLidar:
        return Lidar(m, sum);
      case Stream::kCloud:
        return Cloud(m, sum);
      case Stream::kImu:
        return Imu(m, sum);
      case Stream::kImage:
        return Image(m, sum);
      case Stream::kEncoder:
        return Encoder(m, sum);
    }
    return Status::Ok();
  }

  /// Writes the packet the last cloud left unfinished (PointCloud2 input).
  Status Finish(BagImportSummary* sum) {
    std::vector<LidarPacket> packets;
    packetizer_.Flush(&packets);
    return WritePackets(packets, sum);
  }

 private:
  /// Rig time of a stamp: one correctly rounded division of exact nanoseconds, so a stamp written from a CSV
  /// time with 9 decimals reads back as the identical double.
  Seconds RigTime(const RosTime& t, BagImportSummary* sum) {
    const Seconds rig = static_cast<double>(t.ToNs() - epoch_ns_) / 1e9;
    Span(rig, sum);
    return rig;
  }

  void Span(Seconds rig, BagImportSummary* sum) {
    if (!seen_any_) sum->first_t_s = sum->last_t_s = rig;
    seen_any_ = true;
    sum->first_t_s = std::min(sum->first_t_s, rig);
    sum->last_t_s = std::max(sum->last_t_s, rig);
  }

  Status Increasing(const BagMessage& m, const RosTime& stamp) {
    auto [it, fresh] = last_ns_.emplace(m.topic, stamp.ToNs());
    if (!fresh) {
      if (stamp.ToNs() <= it->second)
        return Status::Error(Where(bag_, m) + "field 'header.stamp': " + std::to_string(stamp.sec) + "." +
                             std::to_string(stamp.nsec) + " s does not increase (previous message at " +
                             std::to_string(it->second) + " ns)");
      it->second = stamp.ToNs();
    }
    return Status::Ok();
  }

  Status Lidar(const BagMessage& m, BagImportSummary* sum) {
    VelodyneScanMsg scan;
    if (Status s = Parse(m.body, &scan); !s) return Status::Error(Where(bag_, m) + s.message);
    LidarPacket packet;
    packet.udp_port = 2368;
    for (const VelodynePacketMsg& p : scan.packets) {
      packet.t_capture_s = RigTime(p.stamp, sum);
      packet.payload.assign(p.data.begin(), p.data.end());
      if (Status s = writer_->Write(packet); !s) return Status::Error(Where(bag_, m) + s.message);
      ++sum->packets;
    }
    ++sum->scans;
    return Status::Ok();
  }

  /// A cloud -> the VLP-16 packets it completes (cloud_to_packets.hpp); the span covers the packets' captures.
  Status Cloud(const BagMessage& m, BagImportSummary* sum) {
    PointCloud2Msg cloud;
    if (Status s = Parse(m.body, &cloud); !s) return Status::Error(Where(bag_, m) + s.message);
    if (Status s = Increasing(m, cloud.header.stamp); !s) return s;
    std::vector<CloudPoint> points;
    if (Status s = ReadCloudPoints(cloud, &points); !s) return Status::Error(Where(bag_, m) + s.message);
    std::vector<LidarPacket> packets;
    const Seconds stamp = RigTime(cloud.header.stamp, sum);
    if (Status s = packetizer_.Add(stamp, points, &packets); !s) return Status::Error(Where(bag_, m) + s.message);
    sum->cloud_points += points.size();
    ++sum->scans;
    if (Status s = WritePackets(packets, sum); !s) return Status::Error(Where(bag_, m) + s.message);
    return Status::Ok();
  }

  Status WritePackets(const std::vector<LidarPacket>& packets, BagImportSummary* sum) {
    for (const LidarPacket& p : packets) {
      if (Status s = writer_->Write(p); !s) return s;
      Span(p.t_capture_s, sum);
      ++sum->packets;
    }
    return Status::Ok();
  }

  Status Imu(const BagMessage& m, BagImportSummary* sum) {
    ImuMsg imu;
    if (Status s = Parse(m.body, &imu); !s) return Status::Error(Where(bag_, m) + s.message);
    if (Status s = Increasing(m, imu.header.stamp); !s) return s;
    ImuSample sample;
    sample.t_s = RigTime(imu.header.stamp, sum);
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(imu.angular_velocity[i]) || !std::isfinite(imu.linear_acceleration[i]))
        return Status::Error(Where(bag_, m) + "field 'angular_velocity' or 'linear_acceleration': not finite");
      sample.gyro_radps[i] = imu.angular_velocity[i];
      sample.accel_mps2[i] = imu.linear_acceleration[i];
    }
    ++sum->imu;
    return writer_->Write(sample);
  }

  Status Encoder(const BagMessage& m, BagImportSummary* sum) {
    JointStateMsg joint;
    if (Status s = Parse(m.body, &joint); !s) return Status::Error(Where(bag_, m) + s.message);
    if (joint.position.empty())
      return Status::Error(Where(bag_, m) + "field 'position': empty (position[0] must hold the motor angle)");
    if (!std::isfinite(joint.position[0])) return Status::Error(Where(bag_, m) + "field 'position[0]': not finite");
    if (Status s = Increasing(m, joint.header.stamp); !s) return s;
    EncoderSample sample;
    sample.t_s = RigTime(joint.header.stamp, sum);
    sample.count =
        EncoderCountFromAngle(joint.position[0], calib_.encoder.counts_per_rev, calib_.encoder.zero_offset_rad);
    ++sum->encoder;
    return writer_->Write(sample);
  }

  Status Image(const BagMessage& m, BagImportSummary* sum) {
    ImageMsg image;
    if (Status s = Parse(m.body, &image); !s) return Status::Error(Where(bag_, m) + s.message);
    int channels = 0, code = -1;
    if (image.encoding == "bgr8") channels = 3;
    if (image.encoding == "rgb8") channels = 3, code = cv::COLOR_RGB2BGR;
    if (image.encoding == "mono8") channels = 1, code = cv::COLOR_GRAY2BGR;
    if (channels == 0)
      return Status::Error(Where(bag_, m) + "field 'encoding': '" + image.encoding +
                           "' is not supported (rgb8, bgr8, mono8)");
    if (image.width == 0 || image.height == 0)
      return Status::Error(Where(bag_, m) + "field 'width'/'height': empty image");
    if (image.step < static_cast<uint64_t>(image.width) * channels)
      return Status::Error(Where(bag_, m) + "field 'step': " + std::to_string(image.step) + " < width x " +
                           std::to_string(channels) + " bytes");
    if (image.data.size() < static_cast<uint64_t>(image.step) * image.height)
      return Status::Error(
          Where(bag_, m) + "field 'data': " + std::to_string(image.data.size()) +
          " bytes, step x height = " + std::to_string(static_cast<uint64_t>(image.step) * image.height));
    if (Status s = Increasing(m, image.header.stamp); !s) return s;
    const cv::Mat view(static_cast<int>(image.height), static_cast<int>(image.width), CV_8UC(channels),
                       image.data.data(), image.step);
    CameraFrame frame;
    frame.t_s = RigTime(image.header.stamp, sum);
    if (code < 0)
      frame.image = view.clone();
    else
      cv::cvtColor(view, frame.image, code);
    if (Status s = writer_->Write(frame); !s) return Status::Error(Where(bag_, m) + s.message);
    ++sum->images;
    return Status::Ok();
  }

  std::string bag_;
  const RigCalib& calib_;
  int64_t epoch_ns_;
  RecordingWriter* writer_;
  CloudPacketizer packetizer_;
  std::map<std::string, int64_t> last_ns_;
  bool seen_any_ = false;
};

Status CheckOutputFolder(const std::string& out_dir, bool force) {
  std::error_code ec;
  if (std::filesystem::exists(out_dir, ec) && !std::filesystem::is_empty(out_dir, ec) && !force)
    return Status::Error(out_dir + ": folder is not empty (use --force to write into it)");
  return Status::Ok();
}

/// The epoch (whole second of the earliest stamp) and the calib moved onto it.
Status ChooseEpoch(const BagReader& bag, const Plan& plan, const BagImportOptions& o, RigCalib* calib,
                   int64_t* epoch_ns) {
  int64_t min_ns = std::numeric_limits<int64_t>::max();
  Status s = bag.ForEach(plan.topics, [&](const BagMessage& m) {
    return EarliestStamp(bag.path(), calib->lidar, plan.streams.at(m.topic), m, &min_ns);
  });
  if (!s) return s;
  if (min_ns == std::numeric_limits<int64_t>::max())
    return Status::Error(bag.path() + ": the chosen topics hold no messages");
  const int64_t epoch_s = min_ns / 1000000000LL;
  *epoch_ns = epoch_s * 1000000000LL;
  const double old_epoch = calib->epoch_unix_s;
  calib->epoch_unix_s = static_cast<double>(epoch_s);
  if (plan.lidar_is_cloud) {  // packets made on the rig clock
    if (o.lidar_clock == LidarClock::kPps)
      return Status::Error(bag.path() + ": --lidar-clock pps applies to raw VelodyneScan packets; the points of " +
                           "a PointCloud2 carry ROS times (the new VLP-16 clock is the rig clock)");
    calib->lidar_clock_offset_s = 0.0;
  } else if (o.lidar_clock == LidarClock::kPps) {
    calib->lidar_clock_offset_s = -static_cast<double>(epoch_s % 3600);
  } else if (old_epoch > 0.0) {
    calib->lidar_clock_offset_s += old_epoch - calib->epoch_unix_s;
  }
  return Status::Ok();
}

}  // namespace

uint32_t EncoderCountFromAngle(double theta_rad, uint32_t counts_per_rev, double zero_offset_rad) {
  const double bins = std::floor((theta_rad + zero_offset_rad) * counts_per_rev / (2.0 * M_PI));
  const double wrapped = bins - std::floor(bins / counts_per_rev) * counts_per_rev;
  return std::min(static_cast<uint32_t>(wrapped), counts_per_rev - 1);
}

Status ImportBag(const std::string& bag_path, const std::string& out_dir, const BagImportOptions& options,
                 BagImportSummary* summary) {
  *summary = BagImportSummary{};
  RigCalib calib;
  if (options.calib_path.empty()) return Status::Error("import: --calib is required (the rig's calib.yaml)");
  if (Status s = LoadCalibYaml(options.calib_path, &calib); !s) return s;
  BagReader bag;
  if (Status s = bag.Open(bag_path); !s) return s;
  Plan plan;
  if (Status s = ChooseTopics(bag, options, &plan, summary); !s) return s;
  int64_t epoch_ns = 0;
  if (Status s = ChooseEpoch(bag, plan, options, &calib, &epoch_ns); !s) return s;
  summary->epoch_unix_s = calib.epoch_unix_s;
  summary->lidar_clock_offset_s = calib.lidar_clock_offset_s;
  if (Status s = CheckOutputFolder(out_dir, options.force); !s) return s;
  RecordingWriter writer;
  if (Status s = writer.Open(out_dir, calib); !s) return s;
  Converter converter(bag.path(), calib, epoch_ns, &writer);
  Status s = bag.ForEach(plan.topics,
                         [&](const BagMessage& m) { return converter.Convert(plan.streams.at(m.topic), m, summary); });
  if (s) s = converter.Finish(summary);
  if (Status c = writer.Close(); s && !c) s = c;
  if (!s) return s;
  if (summary->packets == 0)
    return Status::Error(bag_path + ": topic " + summary->lidar_topic + " holds no packets (or no cloud points)");
  if (summary->encoder < 2)
    return Status::Error(bag_path + ": topic " + summary->encoder_topic + ": " + std::to_string(summary->encoder) +
                         " messages, a recording needs at least 2 encoder samples");
  return Status::Ok();
}

}  // namespace rotolidar::bench::rosmsg
