#include "bench/ros/bag_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <vector>

#include "bench/ros/bag_io.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/io/recording.hpp"
#include "core/io/trajectory_io.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

/// Rig time -> ROS time: the epoch split into whole seconds and a fraction so that no nanosecond is lost.
class StampClock {
 public:
  explicit StampClock(double epoch_unix_s)
      : whole_s_(std::floor(epoch_unix_s)),
        epoch_ns_(static_cast<int64_t>(whole_s_) * 1000000000LL + std::llround((epoch_unix_s - whole_s_) * 1e9)) {}
  Status Stamp(Seconds t_s, const std::string& what, RosTime* out) const {
    if (!std::isfinite(t_s)) return Status::Error(what + ": time is not finite");
    return RosTimeFromNs(epoch_ns_ + std::llround(t_s * 1e9), what, out);
  }

 private:
  double whole_s_;
  int64_t epoch_ns_;
};

enum class Kind { kScan, kImu, kEncoder, kImage };
struct Event {
  Seconds t_s;
  Kind kind;
  std::size_t index;
};

/// Data packets grouped into scans: [begin, end) indices into `data`.
struct Scans {
  std::vector<const LidarPacket*> data;
  std::vector<std::pair<std::size_t, std::size_t>> ranges;
};

int DriverPacketsPerScan(const Recording& rec, const Scans& scans) {
  bool dual = false;
  if (!scans.data.empty() && scans.data.front()->payload.size() == kVelodynePacketBytes)
    dual = scans.data.front()->payload[1204] == static_cast<uint8_t>(Vlp16ReturnMode::kDual);
  const double packet_rate = dual ? 1508.0 : 754.0;
  const double rpm = rec.calib.lidar.rpm > 0.0 ? rec.calib.lidar.rpm : 600.0;
  return static_cast<int>(std::ceil(packet_rate / (rpm / 60.0)));
}

Scans GroupPackets(const Recording& rec, int packets_per_scan, BagExportSummary* sum) {
  Scans scans;
  for (const LidarPacket& p : rec.lidar_packets) {
    if (p.udp_port == kVlp16DataPort && p.payload.size() == kVelodynePacketBytes)
      scans.data.push_back(&p);
    else
      ++sum->dropped_position_packets;
  }
  const std::size_t n = packets_per_scan > 0 ? packets_per_scan : DriverPacketsPerScan(rec, scans);
  for (std::size_t b = 0; b < scans.data.size(); b += n)
    scans.ranges.push_back({b, std::min(b + n, scans.data.size())});
  return scans;
}

Status WriteScan(BagWriter& bag, const StampClock& clock, const Scans& scans, std::size_t i,
                 const BagExportOptions& o) {
  VelodyneScanMsg msg;
  msg.header.seq = static_cast<uint32_t>(i);
  msg.header.frame_id = "velodyne";
  for (std::size_t k = scans.ranges[i].first; k < scans.ranges[i].second; ++k) {
    VelodynePacketMsg p;
    if (Status s = clock.Stamp(scans.data[k]->t_capture_s, "lidar packet " + std::to_string(k), &p.stamp); !s) return s;
    std::memcpy(p.data.data(), scans.data[k]->payload.data(), kVelodynePacketBytes);
    msg.packets.push_back(p);
  }
  msg.header.stamp = msg.packets.back().stamp;
  return bag.WriteMsg(o.lidar_topic, msg.header.stamp, msg);
}

Status WriteImu(BagWriter& bag, const StampClock& clock, const ImuSample& s, std::size_t i, const BagExportOptions& o) {
  ImuMsg msg;
  msg.header.seq = static_cast<uint32_t>(i);
  msg.header.frame_id = "imu";
  if (Status st = clock.Stamp(s.t_s, "imu.csv sample " + std::to_string(i), &msg.header.stamp); !st) return st;
  msg.orientation_covariance[0] = -1.0;  // no orientation estimate (sensor_msgs/Imu's convention)
  for (int k = 0; k < 3; ++k) {
    msg.angular_velocity[k] = s.gyro_radps[k];
    msg.linear_acceleration[k] = s.accel_mps2[k];
  }
  return bag.WriteMsg(o.imu_topic, msg.header.stamp, msg);
}

Status WriteEncoder(BagWriter& bag, const StampClock& clock, const RigCalib& calib, const EncoderSample& s,
                    std::size_t i, const BagExportOptions& o) {
  JointStateMsg msg;
  msg.header.seq = static_cast<uint32_t>(i);
  if (Status st = clock.Stamp(s.t_s, "encoder.csv sample " + std::to_string(i), &msg.header.stamp); !st) return st;
  msg.name = {o.joint_name};
  msg.position = {calib.EncoderAngle(s.count)};
  return bag.WriteMsg(o.encoder_topic, msg.header.stamp, msg);
}

Status WriteImage(BagWriter& bag, const StampClock& clock, const CameraFrameRef& ref, std::size_t i,
                  const BagExportOptions& o) {
  CameraFrame frame;
  if (Status s = LoadCameraFrame(ref, &frame); !s) return s;
  cv::Mat image = frame.image.isContinuous() ? frame.image : frame.image.clone();
  if (image.type() != CV_8UC3) return Status::Error(ref.image_path + ": not an 8-bit 3-channel image");
  ImageMsg msg;
  msg.header.seq = static_cast<uint32_t>(i);
  msg.header.frame_id = "camera";
  if (Status s = clock.Stamp(ref.t_s, "camera frame " + std::to_string(i), &msg.header.stamp); !s) return s;
  msg.height = static_cast<uint32_t>(image.rows);
  msg.width = static_cast<uint32_t>(image.cols);
  msg.encoding = "bgr8";
  msg.step = msg.width * 3;
  msg.data.assign(image.data, image.data + static_cast<std::size_t>(msg.step) * msg.height);
  return bag.WriteMsg(o.image_topic, msg.header.stamp, msg);
}

std::vector<Event> TimeOrder(const Recording& rec, const Scans& scans) {
  std::vector<Event> events;
  for (std::size_t i = 0; i < scans.ranges.size(); ++i)
    events.push_back({scans.data[scans.ranges[i].second - 1]->t_capture_s, Kind::kScan, i});
  for (std::size_t i = 0; i < rec.imu.size(); ++i) events.push_back({rec.imu[i].t_s, Kind::kImu, i});
  for (std::size_t i = 0; i < rec.encoder.size(); ++i) events.push_back({rec.encoder[i].t_s, Kind::kEncoder, i});
  for (std::size_t i = 0; i < rec.camera.size(); ++i) events.push_back({rec.camera[i].t_s, Kind::kImage, i});
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.t_s < b.t_s; });
  return events;
}

}  // namespace

Status ExportRecordingToBag(const std::string& recording_dir, const std::string& bag_path, const BagExportOptions& o,
                            BagExportSummary* sum) {
  *sum = BagExportSummary{};
  Recording rec;
  if (Status s = LoadRecording(recording_dir, &rec); !s) return s;
  sum->epoch_unix_s = o.epoch_unix_s >= 0.0          ? o.epoch_unix_s
                      : rec.calib.epoch_unix_s > 0.0 ? rec.calib.epoch_unix_s
                                                     : kDefaultBagEpochUnixS;
  const StampClock clock(sum->epoch_unix_s);
  const Scans scans = GroupPackets(rec, o.packets_per_scan, sum);
  BagWriter bag;
  if (Status s = bag.Open(bag_path); !s) return s;
  for (const Event& e : TimeOrder(rec, scans)) {
    Status s;
    switch (e.kind) {
      case Kind::kScan:
        s = WriteScan(bag, clock, scans, e.index, o);
        break;
      case Kind::kImu:
        s = WriteImu(bag, clock, rec.imu[e.index], e.index, o);
        break;
      case Kind::kEncoder:
        s = WriteEncoder(bag, clock, rec.calib, rec.encoder[e.index], e.index, o);
        break;
      case Kind::kImage:
        s = WriteImage(bag, clock, rec.camera[e.index], e.index, o);
        break;
    }
    if (!s) return s;
  }
  sum->scans = scans.ranges.size();
  sum->packets = scans.data.size();
  sum->imu = rec.imu.size();
  sum->encoder = rec.encoder.size();
  sum->images = rec.camera.size();
  sum->messages = bag.written();
  return bag.Close();
}

namespace {

PointCloud2Msg MapCloud(const std::vector<Eigen::Vector3d>& points, const RosTime& stamp) {
  PointCloud2Msg msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = "world";
  msg.height = 1;
  msg.width = static_cast<uint32_t>(points.size());
  const auto f32 = static_cast<uint8_t>(PointFieldType::kFloat32);
  msg.fields = {{"x", 0, f32, 1}, {"y", 4, f32, 1}, {"z", 8, f32, 1}};
  msg.point_step = 12;
  msg.row_step = msg.point_step * msg.width;
  msg.is_dense = 1;
  msg.data.resize(static_cast<std::size_t>(msg.row_step));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const float xyz[3] = {static_cast<float>(points[i].x()), static_cast<float>(points[i].y()),
                          static_cast<float>(points[i].z())};
    std::memcpy(msg.data.data() + 12 * i, xyz, 12);  // little-endian hosts only (x86, ARM), as ROS itself
  }
  return msg;
}

Status WritePose(BagWriter& bag, const RosTime& stamp, const StampedPose& pose, std::size_t i,
                 const BagExportOptions& o) {
  const Eigen::Vector3d p = pose.T_ref_body.translation();
  const Eigen::Quaterniond q(pose.T_ref_body.rotation());
  OdometryMsg odom;
  odom.header.seq = static_cast<uint32_t>(i);
  odom.header.stamp = stamp;
  odom.header.frame_id = "world";
  odom.child_frame_id = "base";
  odom.position = {p.x(), p.y(), p.z()};
  odom.orientation_xyzw = {q.x(), q.y(), q.z(), q.w()};
  if (Status s = bag.WriteMsg(o.odom_topic, stamp, odom); !s) return s;
  TFMessageMsg tf;
  tf.transforms.resize(1);
  tf.transforms[0].header = odom.header;
  tf.transforms[0].child_frame_id = "base";
  tf.transforms[0].translation = odom.position;
  tf.transforms[0].rotation_xyzw = odom.orientation_xyzw;
  return bag.WriteMsg("/tf", stamp, tf);
}

}  // namespace

Status ExportRunToBag(const std::string& run_dir, const std::string& bag_path, const BagExportOptions& o,
                      BagExportSummary* sum) {
  *sum = BagExportSummary{};
  Trajectory traj;
  if (Status s = ReadTrajectory(run_dir + "/trajectory.tum", TrajectoryFormat::kTum, &traj); !s) return s;
  std::vector<Eigen::Vector3d> map;
  const std::string map_path = run_dir + "/map.ply";
  if (std::filesystem::exists(map_path)) {
    if (Status s = LoadPointCloud(map_path, &map); !s) return s;
  }
  sum->epoch_unix_s = o.epoch_unix_s >= 0.0 ? o.epoch_unix_s : kDefaultBagEpochUnixS;
  const StampClock clock(sum->epoch_unix_s);
  BagWriter bag;
  if (Status s = bag.Open(bag_path); !s) return s;
  for (std::size_t i = 0; i < traj.size(); ++i) {
    RosTime stamp;
    if (Status s = clock.Stamp(traj[i].t_s, "trajectory.tum pose " + std::to_string(i), &stamp); !s) return s;
    if (i == 0 && !map.empty()) {
      if (Status s = bag.WriteMsg(o.map_topic, stamp, MapCloud(map, stamp), /*latched=*/true); !s) return s;
    }
    if (Status s = WritePose(bag, stamp, traj[i], i, o); !s) return s;
  }
  sum->poses = traj.size();
  sum->map_points = map.size();
  sum->messages = bag.written();
  return bag.Close();
}

}  // namespace rotolidar::bench::rosmsg
