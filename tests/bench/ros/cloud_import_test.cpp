// sensor_msgs/PointCloud2 as LiDAR input of `rotolidar import` (bench/ros/cloud_to_packets.hpp):
//  - the azimuth/elevation/time conventions on hand-made points (one firing sequence of all 16 lasers);
//  - sim -> VLP-16 packets -> decoded points -> one PointCloud2 per VelodyneScan (the driver's layout: x, y, z,
//    intensity float32, ring uint16, time float32 relative to header.stamp = the scan's last packet stamp, so most
//    times are negative) -> bag -> import -> lidar.pcap decoded: the same points (laser, range within 2 mm,
//    azimuth within 0.01 deg, intensity) at the same times (within 1 us); SLAM on it against the VelodyneScan import;
// Malformed clouds: cloud_errors_test.cpp.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>

#include "bench/ros/bag_export.hpp"
#include "bench/ros/bag_import.hpp"
#include "bench/ros/bag_io.hpp"
#include "bench/ros/cloud_to_packets.hpp"
#include "tests/bench/ros/cloud_test_util.hpp"
#include "bench/run/slam_run.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"
#include "core/wire/vlp16.hpp"
#include "sim/sim_runner.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

namespace fs = std::filesystem;
using namespace cloudtest;  // NOLINT: the test helpers

/// A fresh folder per process (ctest may run two tests of this file at once).
std::string FreshDir(const std::string& name) {
  const std::string dir = (fs::temp_directory_path() / (name + "_" + std::to_string(getpid()))).string();
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// Azimuth difference [deg] folded into [0, 180].
double AzimuthDiffDeg(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return std::min(d, 360.0 - d);
}

struct Diffs {
  double range_m = 0.0, azimuth_deg = 0.0, t_s = 0.0;
};

/// Compares two decoded streams point by point (both sorted by firing-sequence time, then laser).
Diffs ComparePoints(std::vector<LidarPoint> a, std::vector<LidarPoint> b, const RigCalib& calib, double dt_b) {
  auto key = [](const LidarPoint& p) { return p.t_s - p.laser_id * kVlp16FiringPeriodS; };
  auto by_firing = [&](const LidarPoint& p, const LidarPoint& q) {
    return std::abs(key(p) - key(q)) > 5e-6 ? key(p) < key(q) : p.laser_id < q.laser_id;
  };
  std::sort(a.begin(), a.end(), by_firing);
  std::sort(b.begin(), b.end(), by_firing);
  Diffs d;
  EXPECT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    const LidarPoint &p = a[i], &q = b[i];
    EXPECT_EQ(p.laser_id, q.laser_id) << "point " << i;
    EXPECT_EQ(p.intensity, q.intensity) << "point " << i;
    if (p.laser_id != q.laser_id) break;
    const Eigen::Vector3d o = Vlp16RayOrigin(calib.lidar.vertical_offset_m[p.laser_id]);
    const double rp = (Eigen::Vector3d(p.x_m, p.y_m, p.z_m) - o).norm();
    const double rq = (Eigen::Vector3d(q.x_m, q.y_m, q.z_m) - o).norm();
    d.range_m = std::max(d.range_m, std::abs(rp - rq));
    d.azimuth_deg = std::max(d.azimuth_deg, AzimuthDiffDeg(p.azimuth_deg, q.azimuth_deg));
    d.t_s = std::max(d.t_s, std::abs(p.t_s - (q.t_s + dt_b)));
  }
  return d;
}

// Hand-made points: one firing sequence, all 16 lasers at head azimuth 90 deg (clockwise from +x seen from above:
// the -y side), 10 m. The packets decode to the same points: laser = the ring's laser, y < 0, azimuth 90 deg
// (+ the decoder's per-laser interpolation, which needs the head speed: rpm 600), times as given.
TEST(CloudToPackets, ConventionsOnOneFiring) {
  RigCalib calib;
  const double t0 = 2.0, az_deg = 90.0;
  const std::array<int, 16> laser_of_ring = LaserOfRing(calib.lidar);
  std::vector<CloudPoint> cloud;
  for (int ring = 0; ring < 16; ++ring) {
    const int laser = laser_of_ring[ring];
    // The head turns 3600 deg/s at 600 rpm: laser l fires 2.304 us x l after laser 0.
    const double az = (az_deg + 3600.0 * laser * kVlp16FiringPeriodS) * M_PI / 180.0;
    const Eigen::Vector3d p = Vlp16RayOrigin(calib.lidar.vertical_offset_m[laser]) +
                              10.0 * Vlp16RayDirection(calib.lidar.elevation_deg[laser] * M_PI / 180.0, az);
    CloudPoint q;
    q.x_m = static_cast<float>(p.x()), q.y_m = static_cast<float>(p.y()), q.z_m = static_cast<float>(p.z());
    q.ring = static_cast<uint16_t>(ring);
    q.intensity = 7.f + ring;
    q.dt_s = laser * kVlp16FiringPeriodS;
    q.index = static_cast<uint32_t>(ring);
    cloud.push_back(q);
  }
  EXPECT_EQ(LaserOfRing(calib.lidar)[0], 0);  // -15 deg
  EXPECT_EQ(LaserOfRing(calib.lidar)[15], 15);  // +15 deg
  EXPECT_EQ(LaserOfRing(calib.lidar)[8], 1);  // +1 deg
  CloudPacketizer packetizer(calib.lidar);
  std::vector<LidarPacket> packets;
  ASSERT_TRUE(packetizer.Add(t0, cloud, &packets).ok);
  EXPECT_TRUE(packets.empty());  // 1 of 24 sequences
  packetizer.Flush(&packets);
  ASSERT_EQ(packets.size(), 1u);
  EXPECT_EQ(packets[0].payload.size(), kVlp16PacketBytes);
  calib.lidar_clock_offset_s = 0.0;
  const std::vector<LidarPoint> points = DecodeAll(packets, calib);
  ASSERT_EQ(points.size(), 16u);
  for (const LidarPoint& p : points) {
    const CloudPoint& q = cloud[p.ring];
    EXPECT_EQ(p.laser_id, laser_of_ring[p.ring]);
    EXPECT_LT(p.y_m, -9.0f);
    EXPECT_NEAR(p.azimuth_deg, az_deg + 3600.0 * p.laser_id * kVlp16FiringPeriodS, 0.01);
    EXPECT_NEAR(p.x_m, q.x_m, 0.002);
    EXPECT_NEAR(p.y_m, q.y_m, 0.002);
    EXPECT_NEAR(p.z_m, q.z_m, 0.002);
    EXPECT_NEAR(p.t_s, t0 + q.dt_s, 1e-9);
    EXPECT_EQ(p.intensity, q.intensity);
  }
}

// Packets as the VLP-16 makes them (72 sequences, 3 packets, 600 rpm), decoded, each packet's points shifted by its
// own stamp error (a driver stamping packets with the host's receive time: 13.7 us, -21.3 us, 40.1 us), as one
// cloud: no common 55.296 us grid, so every driver packet starts a packet of its own. Laser 0 is missing from odd
// sequences and from block 5 (the block azimuth comes from another laser, moved back by the measured head speed),
// sequence 24 (the second packet's first) and block 15 are empty. Decoded again: the same points within 2 mm and
// 0.01 deg, at the shifted times within 0.5 us (the packet timestamp's rounding to whole microseconds).
TEST(CloudToPackets, JitteredDriverPacketsRoundTrip) {
  RigCalib calib;
  calib.lidar_clock_offset_s = 0.0;
  Vlp16PacketEncoder encoder(Vlp16ReturnMode::kStrongest, 0.0);
  std::vector<LidarPacket> packets;
  for (int s = 0; s < 72; ++s) {
    Vlp16FiringSequence seq;
    seq.t_s = 5.000017 + s * kVlp16SequencePeriodS;
    seq.azimuth_centideg = static_cast<uint16_t>(std::lround(1234.0 + 360000.0 * s * kVlp16SequencePeriodS));
    for (int l = 0; l < 16; ++l) {
      const bool empty = s == 24 || s / 2 == 15 || (l == 0 && (s % 2 == 1 || s / 2 == 5));
      seq.distance_2mm[l] = empty ? 0 : static_cast<uint16_t>(2500 + 50 * l + 7 * s);
      seq.reflectivity[l] = static_cast<uint8_t>(l + s);
    }
    if (std::optional<LidarPacket> p = encoder.Add(seq)) packets.push_back(*p);
  }
  ASSERT_EQ(packets.size(), 3u);
  Vlp16DecoderConfig config;
  Vlp16Decoder decoder(calib.lidar, config);
  const double jitter_s[3] = {13.7e-6, -21.3e-6, 40.1e-6};
  const Seconds stamp = 5.0;
  std::vector<LidarPoint> original;
  std::vector<CloudPoint> cloud;
  for (int k = 0; k < 3; ++k) {
    std::vector<LidarPoint> points;
    ASSERT_TRUE(decoder.Decode(packets[k], &points).ok);
    for (const LidarPoint& p : points) {
      CloudPoint q;
      q.x_m = p.x_m, q.y_m = p.y_m, q.z_m = p.z_m, q.intensity = p.intensity, q.ring = p.ring;
      q.dt_s = static_cast<float>(p.t_s + jitter_s[k] - stamp);
      q.index = static_cast<uint32_t>(cloud.size());
      cloud.push_back(q);
      original.push_back(p);
      original.back().t_s += jitter_s[k];
    }
  }
  CloudPacketizer packetizer(calib.lidar);
  std::vector<LidarPacket> out;
  ASSERT_TRUE(packetizer.Add(stamp, cloud, &out).ok);
  packetizer.Flush(&out);
  EXPECT_NEAR(packetizer.rate_centideg_per_s(), 360000.0, 3600.0);  // 600 rpm, from the points
  EXPECT_EQ(out.size(), 3u);
  const Diffs d = ComparePoints(original, DecodeAll(out, calib), calib, 0.0);
  std::printf("jittered packets: max |d range| %.3g m, max |d azimuth| %.3g deg, max |d t| %.3g s\n", d.range_m,
              d.azimuth_deg, d.t_s);
  EXPECT_LE(d.range_m, 0.002);
  EXPECT_LE(d.azimuth_deg, 0.01);
  EXPECT_LE(d.t_s, 0.5e-6 + 1e-9);
}

/// Reads `bag` and writes it again as `out` with each VelodyneScan also as a PointCloud2 on /velodyne_points:
/// the scan's packets decoded (one decoder over the stream), stamped as the scan (its last packet's capture).
/// Returns the decoded points (original rig clock) and the number of clouds.
std::vector<LidarPoint> AddClouds(const std::string& bag, const std::string& out, const RigCalib& calib,
                                  std::size_t* clouds) {
  BagReader reader;
  EXPECT_TRUE(reader.Open(bag));
  BagWriter writer;
  EXPECT_TRUE(writer.Open(out));
  Vlp16DecoderConfig config;
  config.lidar_clock_offset_s = calib.lidar_clock_offset_s;
  Vlp16Decoder decoder(calib.lidar, config);
  std::vector<LidarPoint> all;
  *clouds = 0;
  const int64_t epoch_ns = static_cast<int64_t>(kDefaultBagEpochUnixS) * 1000000000LL;
  const Status s = reader.ForEach({"/velodyne_packets", "/imu/data", "/joint_states"}, [&](const BagMessage& m) {
    const RosMsgType& type = m.topic == "/imu/data"        ? ImuMsg::Type()
                             : m.topic == "/joint_states" ? JointStateMsg::Type()
                                                          : VelodyneScanMsg::Type();
    if (Status w = writer.Write(m.topic, m.time, type, m.body); !w) return w;
    if (m.topic != "/velodyne_packets") return Status::Ok();
    VelodyneScanMsg scan;
    if (Status p = Parse(m.body, &scan); !p) return p;
    std::vector<LidarPoint> points;
    for (const VelodynePacketMsg& vp : scan.packets) {
      LidarPacket packet;
      packet.payload.assign(vp.data.begin(), vp.data.end());
      if (Status d = decoder.Decode(packet, &points); !d) return d;
    }
    all.insert(all.end(), points.begin(), points.end());
    ++*clouds;
    const Seconds stamp_rig = static_cast<double>(scan.header.stamp.ToNs() - epoch_ns) / 1e9;
    return writer.WriteMsg("/velodyne_points", m.time, MakeCloud(scan.header.stamp, points, stamp_rig));
  });
  EXPECT_TRUE(s.ok) << s.message;
  EXPECT_TRUE(writer.Close());
  return all;
}

/// Max pose differences between two trajectories of the same length; b's clock reads a's - dt_b.
Diffs CompareTrajectories(const Trajectory& a, const Trajectory& b, double dt_b, double* max_angle_rad) {
  Diffs d;
  *max_angle_rad = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    d.t_s = std::max(d.t_s, std::abs(a[i].t_s - (b[i].t_s + dt_b)));
    d.range_m = std::max(d.range_m, (a[i].T_ref_body.translation() - b[i].T_ref_body.translation()).norm());
    *max_angle_rad = std::max(
        *max_angle_rad, Eigen::AngleAxisd(a[i].T_ref_body.rotation().transpose() * b[i].T_ref_body.rotation()).angle());
  }
  return d;
}

/// A 3 s typical-realism sim in dir/recording, exported as dir/rec.bag, rewritten as dir/both.bag with the clouds.
void SimulateWithClouds(const std::string& dir, std::vector<LidarPoint>* points, std::size_t* clouds,
                        BagExportSummary* exported) {
  sim::SimConfig config = sim::PresetSimConfig(sim::Realism::kTypical);
  config.duration_s = 3.0;
  config.camera.enabled = false;
  sim::SimSummary sim_summary;
  ASSERT_TRUE(sim::RunSimulation(config, dir + "/recording", &sim_summary).ok);
  Recording original;
  ASSERT_TRUE(LoadRecording(dir + "/recording", &original).ok);
  ASSERT_TRUE(ExportRecordingToBag(dir + "/recording", dir + "/rec.bag", BagExportOptions{}, exported).ok);
  *points = AddClouds(dir + "/rec.bag", dir + "/both.bag", original.calib, clouds);
  ASSERT_GT(points->size(), 100000u);
}

/// No --lidar-topic on a bag with both kinds: the error lists both.
void ExpectAmbiguousLidar(const std::string& dir, BagImportOptions options) {
  BagImportSummary summary;
  const Status s = ImportBag(dir + "/both.bag", dir + "/ambiguous", options, &summary);
  ASSERT_FALSE(s.ok);
  for (const char* part : {"several velodyne_msgs/VelodyneScan or sensor_msgs/PointCloud2 topics: /velodyne_packets "
                           "(velodyne_msgs/VelodyneScan",
                           "/velodyne_points (sensor_msgs/PointCloud2", "choose one with --lidar-topic"})
    EXPECT_NE(s.message.find(part), std::string::npos) << s.message;
}

/// SLAM on dir/packets (the VelodyneScan import) and dir/cloud (the PointCloud2 import of the same bag).
void ExpectSameTrajectory(const std::string& dir) {
  Recording by_packets, by_clouds;
  ASSERT_TRUE(LoadRecording(dir + "/packets", &by_packets).ok);
  ASSERT_TRUE(LoadRecording(dir + "/cloud", &by_clouds).ok);
  SlamRunResult from_packets, from_clouds;
  ASSERT_TRUE(RunSlam(dir + "/packets", EstimatorConfig{}, dir + "/slam_packets", &from_packets).ok);
  ASSERT_TRUE(RunSlam(dir + "/cloud", EstimatorConfig{}, dir + "/slam_clouds", &from_clouds).ok);
  ASSERT_GT(from_packets.trajectory.size(), 10u);
  ASSERT_EQ(from_clouds.trajectory.size(), from_packets.trajectory.size());
  double max_angle = 0.0;
  const Diffs t = CompareTrajectories(from_packets.trajectory, from_clouds.trajectory,
                                      by_clouds.calib.epoch_unix_s - by_packets.calib.epoch_unix_s, &max_angle);
  std::printf("slam packets vs clouds: %zu poses, max |dt| %.3g s, max |dp| %.3g m, max angle %.3g rad\n",
              from_packets.trajectory.size(), t.t_s, t.range_m, max_angle);
  // The estimator gets the same points (float32 positions equal, times equal up to the last bits of the different
  // clock offset: 7e-16 s in the test below); measured 31 poses, max |dp| 1.8e-10 m, max angle 4.8e-11 rad, |dt|
  // 4e-16 s (2026-12-05). Inputs equal up to rounding get the bounds of the VelodyneScan round trip
  // (bag_roundtrip_test.cpp: 1 um, 1 urad), ~5000x the measured difference; times within 1 ns.
  EXPECT_LT(t.t_s, 1e-9);
  EXPECT_LT(t.range_m, 1e-6);
  EXPECT_LT(max_angle, 1e-6);
}

TEST(CloudImport, SimCloudsImportToTheSamePointsAndTrajectory) {
  const std::string dir = FreshDir("rotolidar_cloud_import");
  std::vector<LidarPoint> points;
  std::size_t clouds = 0;
  BagExportSummary exported;
  SimulateWithClouds(dir, &points, &clouds, &exported);
  if (HasFatalFailure()) return;
  BagImportOptions options;
  options.calib_path = dir + "/recording/calib.yaml";
  ExpectAmbiguousLidar(dir, options);

  options.lidar_topic = "/velodyne_points";
  BagImportSummary summary;
  const auto start = std::chrono::steady_clock::now();
  const Status imported = ImportBag(dir + "/both.bag", dir + "/cloud", options, &summary);
  const double import_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(imported.ok) << imported.message;
  EXPECT_EQ(summary.scans, clouds);
  EXPECT_EQ(summary.cloud_points, points.size());
  Recording rec;
  ASSERT_TRUE(LoadRecording(dir + "/cloud", &rec).ok);
  EXPECT_EQ(rec.calib.lidar_clock_offset_s, 0.0);
  // The original rig clock is the bag's stamps - kDefaultBagEpochUnixS; the import's is stamps - its epoch.
  const double dt = rec.calib.epoch_unix_s - kDefaultBagEpochUnixS;
  const Diffs d = ComparePoints(points, DecodeAll(rec.lidar_packets, rec.calib), rec.calib, dt);
  std::printf("cloud import: %zu clouds, %zu points, %zu packets (VelodyneScan: %zu) in %.2f s; max |d range| "
              "%.3g m, max |d azimuth| %.3g deg, max |d t| %.3g s\n",
              clouds, points.size(), summary.packets, exported.packets, import_s, d.range_m, d.azimuth_deg, d.t_s);
  EXPECT_LE(d.range_m, 0.002);
  EXPECT_LE(d.azimuth_deg, 0.01);
  EXPECT_LE(d.t_s, 1e-6);
  // The driver's clouds hold whole packets and the sim's firings keep one grid: the same packets come back.
  EXPECT_EQ(summary.packets, exported.packets);

  // The same bag's VelodyneScan topic, picked by the flag, against the clouds.
  options.lidar_topic = "/velodyne_packets";
  ASSERT_TRUE(ImportBag(dir + "/both.bag", dir + "/packets", options, &summary).ok);
  EXPECT_EQ(summary.cloud_points, 0u);
  fs::remove_all(dir + "/both.bag");
  ExpectSameTrajectory(dir);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rotolidar::bench::rosmsg
