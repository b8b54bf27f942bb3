// `rotolidar import BAG OUT_DIR` and `rotolidar export-bag`: ROS 1 bags in and out (docs/ros.md).
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/ros/bag_export.hpp"
#include "bench/ros/bag_import.hpp"

namespace rotolidar::bench {

int CmdImport(int argc, char** argv) {
  OptionParser p("import",
                 "Convert a ROS 1 bag (velodyne_msgs/VelodyneScan, sensor_msgs/Imu, JointState, Image) "
                 "into a recording folder. Rig time = stamp - epoch_unix_s, the epoch being the whole "
                 "second of the earliest stamp (written into calib.yaml). See docs/ros.md.");
  p.AddPositional("BAG", "the ROS 1 bag (.bag)");
  p.AddPositional("OUT_DIR", "the recording folder to write");
  p.Add("calib", "", "-", "the rig's calib.yaml (required): geometry, encoder counts_per_rev and zero offset");
  p.Add("lidar-topic", "", "-", "velodyne_msgs/VelodyneScan, or sensor_msgs/PointCloud2 with ring and time (or t) "
                                "fields; empty = the only one in the bag");
  p.Add("imu-topic", "", "-", "sensor_msgs/Imu topic (its frame = the rig's imu frame); empty = the only one");
  p.Add("encoder-topic", "", "-",
        "sensor_msgs/JointState topic, position[0] = motor angle [rad]; empty = the only one");
  p.Add("image-topic", "", "-",
        "sensor_msgs/Image topic (rgb8, bgr8, mono8); empty = the only one if any; none = no camera");
  p.Add("lidar-clock", "calib", "-",
        "VLP-16 clock: calib (calib.yaml's lidar_clock_offset_s, moved to the new "
        "epoch) or pps (head PPS-locked to UTC, stamps are UTC)");
  p.AddFlag("force", "write into a non-empty OUT_DIR");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  rosmsg::BagImportOptions o;
  o.calib_path = p.Get("calib");
  if (o.calib_path.empty()) return std::cerr << "error: import: --calib FILE is required (see --help)\n", 2;
  o.lidar_topic = p.Get("lidar-topic");
  o.imu_topic = p.Get("imu-topic");
  o.encoder_topic = p.Get("encoder-topic");
  o.image_topic = p.Get("image-topic");
  o.force = p.Flag("force");
  const std::string clock = p.Get("lidar-clock");
  if (clock != "calib" && clock != "pps") return std::cerr << "error: import: --lidar-clock must be calib or pps\n", 2;
  o.lidar_clock = clock == "pps" ? rosmsg::LidarClock::kPps : rosmsg::LidarClock::kCalib;
  rosmsg::BagImportSummary sum;
  if (Status s = rosmsg::ImportBag(p.Get("BAG"), p.Get("OUT_DIR"), o, &sum); !s) return Fail(s);
  std::printf("import: %s -> %s\n", p.Get("BAG").c_str(), p.Get("OUT_DIR").c_str());
  std::printf("  lidar  : %s, %zu scans, %zu packets\n", sum.lidar_topic.c_str(), sum.scans, sum.packets);
  std::printf("  imu    : %s, %zu samples\n", sum.imu_topic.c_str(), sum.imu);
  std::printf("  encoder: %s, %zu samples\n", sum.encoder_topic.c_str(), sum.encoder);
  std::printf("  camera : %s, %zu images\n", sum.image_topic.empty() ? "(none)" : sum.image_topic.c_str(), sum.images);
  std::printf("  clock  : epoch_unix_s %.0f, lidar_clock_offset_s %.9g, rig time %.6f .. %.6f s\n", sum.epoch_unix_s,
              sum.lidar_clock_offset_s, sum.first_t_s, sum.last_t_s);
  return 0;
}

int CmdExportBag(int argc, char** argv) {
  OptionParser p("export-bag",
                 "Write a slam run (trajectory.tum as nav_msgs/Odometry + /tf, map.ply as one "
                 "PointCloud2) or, with --recording, a recording folder (VelodyneScan, Imu, JointState, "
                 "Image) as a ROS 1 bag. See docs/ros.md.");
  p.AddPositional("INPUT", "a slam run folder (slam --out), or a recording folder with --recording");
  p.AddPositional("OUT_BAG", "the bag to write (overwritten)");
  p.AddFlag("recording", "INPUT is a recording folder: write its sensor streams");
  p.Add("epoch-unix-s", "auto", "s",
        "Unix time of rig time 0; auto = the recording's calib epoch_unix_s, or "
        "1700000000 when it is 0 (sim recordings) and for runs");
  p.Add("packets-per-scan", "0", "-", "VLP-16 packets per VelodyneScan; 0 = as the driver: ceil(754 / (rpm/60))");
  p.Add("lidar-topic", "/velodyne_packets", "-", "VelodyneScan topic (--recording)");
  p.Add("imu-topic", "/imu/data", "-", "Imu topic (--recording)");
  p.Add("encoder-topic", "/joint_states", "-", "JointState topic (--recording)");
  p.Add("image-topic", "/camera/image_raw", "-", "Image topic (--recording)");
  p.Add("odom-topic", "/rotolidar/odometry", "-", "Odometry topic (runs)");
  p.Add("map-topic", "/rotolidar/map", "-", "map PointCloud2 topic (runs)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  rosmsg::BagExportOptions o;
  if (p.Get("epoch-unix-s") != "auto") {
    if (Status s = p.GetDouble("epoch-unix-s", &o.epoch_unix_s); !s)
      return std::cerr << "error: " << s.message << "\n", 2;
    if (!(o.epoch_unix_s > 0.0)) return std::cerr << "error: export-bag: --epoch-unix-s must be > 0\n", 2;
  }
  long packets = 0;
  if (Status s = p.GetInt("packets-per-scan", &packets); !s) return std::cerr << "error: " << s.message << "\n", 2;
  if (packets < 0) return std::cerr << "error: export-bag: --packets-per-scan must be >= 0\n", 2;
  o.packets_per_scan = static_cast<int>(packets);
  o.lidar_topic = p.Get("lidar-topic");
  o.imu_topic = p.Get("imu-topic");
  o.encoder_topic = p.Get("encoder-topic");
  o.image_topic = p.Get("image-topic");
  o.odom_topic = p.Get("odom-topic");
  o.map_topic = p.Get("map-topic");
  rosmsg::BagExportSummary sum;
  const std::string in = p.Get("INPUT"), out = p.Get("OUT_BAG");
  if (p.Flag("recording")) {
    if (Status s = rosmsg::ExportRecordingToBag(in, out, o, &sum); !s) return Fail(s);
    std::printf("export-bag: %s -> %s: %zu messages, epoch_unix_s %.0f\n", in.c_str(), out.c_str(), sum.messages,
                sum.epoch_unix_s);
    std::printf("  %zu VelodyneScan (%zu packets; %zu position packets dropped), %zu Imu, %zu JointState, %zu Image\n",
                sum.scans, sum.packets, sum.dropped_position_packets, sum.imu, sum.encoder, sum.images);
    return 0;
  }
  if (!std::filesystem::exists(in + "/trajectory.tum") && std::filesystem::exists(in + "/calib.yaml"))
    return Fail(Status::Error(in + ": a recording folder, not a slam run: add --recording"));
  if (Status s = rosmsg::ExportRunToBag(in, out, o, &sum); !s) return Fail(s);
  std::printf("export-bag: %s -> %s: %zu poses (Odometry + /tf), map %zu points, epoch_unix_s %.0f\n", in.c_str(),
              out.c_str(), sum.poses, sum.map_points, sum.epoch_unix_s);
  return 0;
}

}  // namespace rotolidar::bench
