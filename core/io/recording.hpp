#pragma once
// The recording folder (docs/recording_format.md): written by the sim or by a real rig's logger, read by core.
//   calib.yaml    rig calibration + format_version
//   lidar.pcap    VLP-16 data (UDP 2368) and position (UDP 8308) packets, Ethernet/IPv4/UDP, libpcap format
//   imu.csv       t_s,gyro_x_radps,gyro_y_radps,gyro_z_radps,accel_x_mps2,accel_y_mps2,accel_z_mps2
//   encoder.csv   t_s,count
//   camera.csv    t_s,index   with images camera/<index as %06d>.png
//   truth/        sim only; never read by core (bench/ reads it)
#include <memory>
#include <string>
#include <vector>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

/// File names inside a recording folder.
struct RecordingLayout {
  static constexpr const char* kCalib = "calib.yaml";
  static constexpr const char* kLidar = "lidar.pcap";
  static constexpr const char* kImu = "imu.csv";
  static constexpr const char* kEncoder = "encoder.csv";
  static constexpr const char* kCamera = "camera.csv";
  static constexpr const char* kCameraDir = "camera";
  static constexpr const char* kTruthDir = "truth";
};

/// A camera frame on disk: the image is loaded on demand (LoadCameraFrame).
struct CameraFrameRef {
  Seconds t_s = 0.0;
  std::string image_path;
};

/// A recording in memory (packets are ~1 MB/s of LiDAR data: minutes fit easily; for longer recordings the loader
/// can leave them in lidar.pcap, and LidarPacketSource streams them from there).
struct Recording {
  std::string dir;
  RigCalib calib;
  std::vector<LidarPacket> lidar_packets;  ///< in capture order; empty when lidar_packets_streamed
  bool lidar_packets_streamed = false;     ///< the packets stay in dir/lidar.pcap (LidarPacketSource reads them)
  std::vector<ImuSample> imu;              ///< strictly increasing t_s
  std::vector<EncoderSample> encoder;      ///< strictly increasing t_s
  std::vector<CameraFrameRef> camera;      ///< strictly increasing t_s; may be empty
};

/// Loads and validates a recording. Every error names the file and line (CSV, YAML) or record (pcap).
/// Missing optional streams (camera) are allowed; calib.yaml, lidar.pcap, imu.csv and encoder.csv are required.
/// A lidar.pcap without VLP-16 data packets (position packets alone included) is an error that names the UDP
/// ports and payload sizes it holds (PcapReader::NoVlp16DataError).
Status LoadRecording(const std::string& dir, Recording* recording);

/// What LoadRecording keeps in memory.
enum class PacketLoading {
  kInMemory,  ///< every LiDAR packet into Recording::lidar_packets
  kStreamed,  ///< none: lidar.pcap is only opened (its errors come from LidarPacketSource while reading)
};
/// LoadRecording with a choice for the packets: kStreamed keeps the memory of a run independent of its length.
Status LoadRecording(const std::string& dir, PacketLoading packets, Recording* recording);

/// A recording's LiDAR packets in capture order, from memory or streamed from its lidar.pcap (one packet in memory
/// at a time). The recording must outlive the source. Not thread-safe.
class LidarPacketSource {
 public:
  LidarPacketSource();
  ~LidarPacketSource();
  LidarPacketSource(const LidarPacketSource&) = delete;
  LidarPacketSource& operator=(const LidarPacketSource&) = delete;

  /// Starts at the first packet. Fails (naming the file) when a streamed lidar.pcap cannot be opened.
  Status Open(const Recording& recording);
  /// The next packet, valid until the next call; nullptr at the end, or at a malformed pcap record (status() then
  /// names the file, the record and the byte offset) or when a streamed file held no VLP-16 data packet at all
  /// (status() says what it held).
  const LidarPacket* Next();
  const Status& status() const { return status_; }
  std::size_t count() const { return count_; }  ///< packets returned so far

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Status status_ = Status::Ok();
  std::size_t count_ = 0;
};

/// Reads an imu.csv (the columns above; strictly increasing t_s) and appends its samples to *samples. Errors name
/// the file, the line and the column.
Status LoadImuCsv(const std::string& path, std::vector<ImuSample>* samples);
/// Writes samples as an imu.csv (overwritten). Fails naming the file when it cannot be written.
Status SaveImuCsv(const std::string& path, const std::vector<ImuSample>& samples);

/// Reads one camera image (BGR8); fails with the file name when it cannot be read.
Status LoadCameraFrame(const CameraFrameRef& ref, CameraFrame* frame);

/// Appends the camera frames of camera.csv in `dir` (none when the file is missing: the stream is optional),
/// without loading the images or the other streams. Errors name the file, the line and the column.
Status LoadCameraIndex(const std::string& dir, std::vector<CameraFrameRef>* out);

/// Streams sensor messages into a new recording folder. Not thread-safe; call Close() to flush.
class RecordingWriter {
 public:
  RecordingWriter();
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  /// Creates `dir` (and parents) and writes calib.yaml. Fails if calib is invalid or the folder is not writable.
  Status Open(const std::string& dir, const RigCalib& calib);
  Status Write(const LidarPacket& packet);
  Status Write(const ImuSample& sample);
  Status Write(const EncoderSample& sample);
  Status Write(const CameraFrame& frame);
  Status Close();
  const std::string& dir() const { return dir_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string dir_;
};

}  // namespace rotolidar
