#include "core/io/recording.hpp"

#include <cstdio>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>

#include "core/io/calib_yaml.hpp"
#include "core/io/csv.hpp"
#include "core/wire/pcap.hpp"
#include "core/util/log.hpp"

namespace fs = std::filesystem;

namespace rotolidar {
namespace {

const std::vector<std::string> kImuColumns{"t_s",          "gyro_x_radps", "gyro_y_radps", "gyro_z_radps",
                                           "accel_x_mps2", "accel_y_mps2", "accel_z_mps2"};
/// One imu.csv row in kImuColumns' order.
std::vector<double> ImuRow(const ImuSample& s) {
  return {s.t_s, s.gyro_radps.x(), s.gyro_radps.y(), s.gyro_radps.z(),
          s.accel_mps2.x(), s.accel_mps2.y(), s.accel_mps2.z()};
}

const std::vector<std::string> kEncoderColumns{"t_s", "count"};
const std::vector<std::string> kCameraColumns{"t_s", "index"};

std::string CameraImageName(long index) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%06ld.png", index);
  return buf;
}

/// Times must increase strictly: a sorted stream is what every consumer assumes.
Status CheckIncreasing(const std::string& path, const CsvReader& reader, Seconds prev, Seconds t) {
  if (t > prev) return Status::Ok();
  return Status::Error(path + ":" + std::to_string(reader.line()) + ": column 1 ('t_s'): time " +
                       std::to_string(t) + " does not increase (previous " + std::to_string(prev) + ")");
}

Status LoadEncoder(const std::string& path, uint32_t counts_per_rev, std::vector<EncoderSample>* out) {
  CsvReader reader;
  if (Status s = reader.Open(path, kEncoderColumns); !s) return s;
  std::vector<double> v;
  while (reader.Next(&v)) {
    if (!out->empty())
      if (Status s = CheckIncreasing(path, reader, out->back().t_s, v[0]); !s) return s;
    if (v[1] < 0 || v[1] >= counts_per_rev || v[1] != static_cast<double>(static_cast<uint32_t>(v[1])))
      return Status::Error(path + ":" + std::to_string(reader.line()) + ": column 2 ('count'): " +
                           std::to_string(v[1]) + " is not an integer in [0, " + std::to_string(counts_per_rev) +
                           ") (calib.yaml encoder.counts_per_rev)");
    out->push_back({v[0], static_cast<uint32_t>(v[1])});
  }
  return reader.status();
}

}  // namespace

Status LoadImuCsv(const std::string& path, std::vector<ImuSample>* out) {
  CsvReader reader;
  if (Status s = reader.Open(path, kImuColumns); !s) return s;
  std::vector<double> v;
  while (reader.Next(&v)) {
    if (!out->empty())
      if (Status s = CheckIncreasing(path, reader, out->back().t_s, v[0]); !s) return s;
    out->push_back({v[0], {v[1], v[2], v[3]}, {v[4], v[5], v[6]}});
  }
  return reader.status();
}

Status SaveImuCsv(const std::string& path, const std::vector<ImuSample>& samples) {
  CsvWriter csv;
  if (Status s = csv.Open(path, kImuColumns); !s) return s;
  for (const ImuSample& s : samples)
    csv.Row(ImuRow(s));
  return csv.Close();
}


Status LoadRecording(const std::string& dir, Recording* recording) {
  return LoadRecording(dir, PacketLoading::kInMemory, recording);
}

Status LoadRecording(const std::string& dir, PacketLoading packets, Recording* recording) {
  Recording r;
  r.dir = dir;
  if (!fs::is_directory(dir)) return Status::Error(dir + ": not a recording folder (no such directory)");
  if (Status s = LoadCalibYaml(dir + "/" + RecordingLayout::kCalib, &r.calib); !s) return s;
  // Packets are read through the streaming source either way (one place for a capture's errors): opening it
  // fails now, not mid-run, when lidar.pcap is missing or not a capture; kInMemory then keeps every packet.
  r.lidar_packets_streamed = true;
  LidarPacketSource source;
  if (Status s = source.Open(r); !s) return s;
  if (packets == PacketLoading::kInMemory) {
    while (const LidarPacket* p = source.Next()) r.lidar_packets.push_back(*p);
    if (!source.status()) return source.status();
    r.lidar_packets_streamed = false;
  }
  if (Status s = LoadImuCsv(dir + "/" + RecordingLayout::kImu, &r.imu); !s) return s;
  if (Status s = LoadEncoder(dir + "/" + RecordingLayout::kEncoder, r.calib.encoder.counts_per_rev, &r.encoder); !s)
    return s;
  if (Status s = LoadCameraIndex(dir, &r.camera); !s) return s;
  if (r.encoder.size() < 2) return Status::Error(dir + "/" + RecordingLayout::kEncoder + ": fewer than 2 samples");
  *recording = std::move(r);
  return Status::Ok();
}

struct LidarPacketSource::Impl {
  const Recording* recording = nullptr;
  PcapReader reader;  // streamed
  LidarPacket packet;
};

LidarPacketSource::LidarPacketSource() : impl_(std::make_unique<Impl>()) {}
LidarPacketSource::~LidarPacketSource() = default;

Status LidarPacketSource::Open(const Recording& recording) {
  impl_ = std::make_unique<Impl>();
  impl_->recording = &recording;
  count_ = 0;
  status_ = Status::Ok();
  if (recording.lidar_packets_streamed)
    status_ = impl_->reader.Open(recording.dir + "/" + RecordingLayout::kLidar, recording.calib.epoch_unix_s);
  return status_;
}

const LidarPacket* LidarPacketSource::Next() {
  const Recording* rec = impl_->recording;
  if (!rec || !status_) return nullptr;
  if (!rec->lidar_packets_streamed)
    return count_ < rec->lidar_packets.size() ? &rec->lidar_packets[count_++] : nullptr;
  if (impl_->reader.Next(&impl_->packet, &status_)) return ++count_, &impl_->packet;
  // The end (or a malformed record): a capture without VLP-16 data gives no points and is an error too.
  if (status_ && impl_->reader.traffic().vlp16_data == 0) status_ = impl_->reader.NoVlp16DataError();
  return nullptr;
}

Status LoadCameraIndex(const std::string& dir, std::vector<CameraFrameRef>* out) {
  const std::string path = dir + "/" + RecordingLayout::kCamera;
  if (!fs::exists(path)) return Status::Ok();  // the camera stream is optional
  CsvReader reader;
  if (Status s = reader.Open(path, kCameraColumns); !s) return s;
  std::vector<double> v;
  while (reader.Next(&v)) {
    if (!out->empty())
      if (Status s = CheckIncreasing(path, reader, out->back().t_s, v[0]); !s) return s;
    const std::string image = dir + "/" + RecordingLayout::kCameraDir + "/" + CameraImageName(long(v[1]));
    if (!fs::exists(image))
      return Status::Error(path + ":" + std::to_string(reader.line()) + ": column 2 ('index'): image " + image +
                           " does not exist");
    out->push_back({v[0], image});
  }
  return reader.status();
}

Status LoadCameraFrame(const CameraFrameRef& ref, CameraFrame* frame) {
  cv::Mat image = cv::imread(ref.image_path, cv::IMREAD_COLOR);
  if (image.empty()) return Status::Error(ref.image_path + ": cannot read image");
  frame->t_s = ref.t_s;
  frame->image = image;
  return Status::Ok();
}

struct RecordingWriter::Impl {
  PcapWriter pcap;
  CsvWriter imu, encoder, camera;
  long camera_index = 0;
  bool camera_open = false;
  double epoch_unix_s = 0.0;
  bool open = false;
};

RecordingWriter::RecordingWriter() : impl_(std::make_unique<Impl>()) {}
// A destructor cannot return the flush's outcome: call Close() to handle it; here it is only logged.
RecordingWriter::~RecordingWriter() {
  if (Status s = Close(); !s) LOG_ERROR(s.message << " (closed by the destructor)");
}

Status RecordingWriter::Open(const std::string& dir, const RigCalib& calib) {
  dir_ = dir;
  std::string why;
  if (!calib.Validate(&why)) return Status::Error("RecordingWriter: invalid calibration: " + why);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Status::Error(dir + ": cannot create folder: " + ec.message());
  impl_->epoch_unix_s = calib.epoch_unix_s;
  if (Status s = SaveCalibYaml(dir + "/" + RecordingLayout::kCalib, calib); !s) return s;
  if (Status s = impl_->pcap.Open(dir + "/" + RecordingLayout::kLidar, calib.epoch_unix_s); !s) return s;
  if (Status s = impl_->imu.Open(dir + "/" + RecordingLayout::kImu, kImuColumns); !s) return s;
  if (Status s = impl_->encoder.Open(dir + "/" + RecordingLayout::kEncoder, kEncoderColumns); !s) return s;
  impl_->open = true;
  return Status::Ok();
}

Status RecordingWriter::Write(const LidarPacket& packet) { return impl_->pcap.Write(packet); }

Status RecordingWriter::Write(const ImuSample& s) {
  impl_->imu.Row(ImuRow(s));
  return Status::Ok();
}

Status RecordingWriter::Write(const EncoderSample& s) {
  impl_->encoder.Row({s.t_s, static_cast<double>(s.count)});
  return Status::Ok();
}

Status RecordingWriter::Write(const CameraFrame& frame) {
  if (!impl_->camera_open) {
    std::error_code ec;
    fs::create_directories(dir_ + "/" + RecordingLayout::kCameraDir, ec);
    if (ec) return Status::Error(dir_ + "/camera: cannot create folder: " + ec.message());
    if (Status s = impl_->camera.Open(dir_ + "/" + RecordingLayout::kCamera, kCameraColumns); !s) return s;
    impl_->camera_open = true;
  }
  const std::string path = dir_ + "/" + RecordingLayout::kCameraDir + "/" + CameraImageName(impl_->camera_index);
  if (!cv::imwrite(path, frame.image)) return Status::Error(path + ": cannot write image");
  impl_->camera.Row({frame.t_s, static_cast<double>(impl_->camera_index++)});
  return Status::Ok();
}

Status RecordingWriter::Close() {
  if (!impl_ || !impl_->open) return Status::Ok();
  impl_->open = false;
  Status status = impl_->pcap.Close();
  for (CsvWriter* w : {&impl_->imu, &impl_->encoder}) {
    Status s = w->Close();
    if (status && !s) status = s;
  }
  if (impl_->camera_open) {
    Status s = impl_->camera.Close();
    if (status && !s) status = s;
    impl_->camera_open = false;
  }
  return status;
}

}  // namespace rotolidar
