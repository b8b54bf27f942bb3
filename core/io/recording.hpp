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

/// A whole recording in memory (packets are ~0.9 MB/s of LiDAR data: minutes fit easily).
struct Recording {
  std::string dir;
  RigCalib calib;
  std::vector<LidarPacket> lidar_packets;  ///< in capture order
  std::vector<ImuSample> imu;              ///< strictly increasing t_s
  std::vector<EncoderSample> encoder;      ///< strictly increasing t_s
  std::vector<CameraFrameRef> camera;      ///< strictly increasing t_s; may be empty
};

/// Loads and validates a recording. Every error names the file and line (CSV, YAML) or record (pcap).
/// Missing optional streams (camera) are allowed; calib.yaml, lidar.pcap, imu.csv and encoder.csv are required.
/// A lidar.pcap without VLP-16 data packets (position packets alone included) is an error that names the UDP
/// ports and payload sizes it holds (PcapReader::NoVlp16DataError).
Status LoadRecording(const std::string& dir, Recording* recording);

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
