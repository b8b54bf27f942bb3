// `rotolidar decode`: packets -> points -> CSV + PLY (contract in decode.hpp).
#include "bench/decode/decode.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <vector>

#include "core/wire/pcap.hpp"
#include "core/wire/scan_splitter.hpp"

namespace rotolidar::bench {
namespace {

const char* FilterName(Vlp16ReturnFilter f) {
  return f == Vlp16ReturnFilter::kStrongest ? "strongest" : f == Vlp16ReturnFilter::kLast ? "last" : "all";
}

/// One source of packets, raw file or pcap, behind PcapReader::Next's contract.
class PacketStream {
 public:
  Status Open(const DecodeOptions& o) {
    raw_ = o.raw;
    if (raw_) return ReadRawVlp16Payloads(o.input_path, &packets_);
    return reader_.Open(o.input_path, o.epoch_unix_s);
  }
  bool Next(LidarPacket* packet, Status* status) {
    if (!raw_) return reader_.Next(packet, status);
    *status = Status::Ok();
    if (next_ >= packets_.size()) return false;
    *packet = std::move(packets_[next_++]);
    return true;
  }
  std::size_t skipped() const { return raw_ ? 0 : reader_.skipped(); }
  /// Why the input held no VLP-16 data packet (none was read): what the pcap held instead, or an empty raw file.
  Status NoDataError(const std::string& path) const {
    if (!raw_) return reader_.NoVlp16DataError();
    return Status::Error(path + ": empty file: no " + std::to_string(kVlp16PacketBytes) + "-byte payloads");
  }
  bool saw_data() const { return raw_ ? !packets_.empty() : reader_.traffic().vlp16_data > 0; }

 private:
  bool raw_ = false;
  std::vector<LidarPacket> packets_;
  std::size_t next_ = 0;
  PcapReader reader_;
};

/// CSV rows stream straight out; PLY vertices go to a body file that Finish() puts behind the header (the
/// vertex count is known only at the end).
class PointWriter {
 public:
  Status Open(const std::string& prefix) {
    csv_path_ = prefix + ".csv";
    ply_path_ = prefix + ".ply";
    body_path_ = ply_path_ + ".body";
    csv_.open(csv_path_);
    body_.open(body_path_, std::ios::binary);
    if (!csv_) return Status::Error(csv_path_ + ": cannot create");
    if (!body_) return Status::Error(body_path_ + ": cannot create");
    csv_ << "x,y,z,intensity,ring,azimuth,return,time_s\n";
    return Status::Ok();
  }
  void Write(const LidarPoint& p) {
    char line[192];
    const int n = std::snprintf(line, sizeof(line), "%.4f,%.4f,%.4f,%.0f,%u,%.3f,%u,%.9f\n", p.x_m, p.y_m, p.z_m,
                                p.intensity, p.ring, p.azimuth_deg, p.return_type, p.t_s);
    csv_.write(line, n);
    unsigned char v[4 * 4 + 1 + 4 + 1 + 8];  // host order = little-endian on every supported target (x86, ARM)
    unsigned char* q = v;
    auto put = [&q](const void* src, std::size_t size) {
      std::memcpy(q, src, size);
      q += size;
    };
    put(&p.x_m, 4), put(&p.y_m, 4), put(&p.z_m, 4), put(&p.intensity, 4), put(&p.ring, 1);
    put(&p.azimuth_deg, 4), put(&p.return_type, 1), put(&p.t_s, 8);
    body_.write(reinterpret_cast<const char*>(v), sizeof(v));
    ++count_;
  }
  Status Finish() {
    csv_.close();
    body_.close();
    if (!csv_) return Status::Error(csv_path_ + ": write error");
    if (!body_) return Status::Error(body_path_ + ": write error");
    std::ofstream ply(ply_path_, std::ios::binary);
    ply << "ply\nformat binary_little_endian 1.0\ncomment rotolidar decode: VLP-16 points, lidar frame [m], "
           "rig time [s]\nelement vertex "
        << count_
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty float intensity\n"
           "property uchar ring\nproperty float azimuth\nproperty uchar return\nproperty double time_s\n"
           "end_header\n";
    std::ifstream body(body_path_, std::ios::binary);
    if (count_ > 0) ply << body.rdbuf();
    body.close();
    std::remove(body_path_.c_str());
    if (!ply) return Status::Error(ply_path_ + ": write error");
    return Status::Ok();
  }
  std::size_t count() const { return count_; }

 private:
  std::string csv_path_, ply_path_, body_path_;
  std::ofstream csv_, body_;
  std::size_t count_ = 0;
};

Status WriteResolvedOptions(const DecodeOptions& o) {
  const std::string path = o.output_prefix + ".decode.yaml";
  std::ofstream out(path);
  out.precision(17);
  out << "input_path: \"" << o.input_path << "\"\nraw: " << (o.raw ? "true" : "false")
      << "\nreturn_filter: " << FilterName(o.decoder.return_filter) << "\nmin_range_m: " << o.decoder.min_range_m
      << "\nmax_range_m: " << o.decoder.max_range_m << "\nlidar_clock_offset_s: " << o.decoder.lidar_clock_offset_s
      << "\nepoch_unix_s: " << o.epoch_unix_s << "\ncut_azimuth_deg: " << o.cut_azimuth_deg
      << "\nrevolution: " << o.revolution << "\nstrict: " << (o.strict ? "true" : "false")
      << "\nkeep_duplicate_dual_returns: " << (o.decoder.keep_duplicate_dual_returns ? "true" : "false") << "\n";
  return out ? Status::Ok() : Status::Error(path + ": cannot write");
}

// Feeds finished scans to the writer (all of them, or only the selected one) and counts them.
void TakeScan(const LidarScan& scan, const DecodeOptions& o, DecodeSummary* summary, PointWriter* writer) {
  const bool selected = o.revolution < 0 || static_cast<std::size_t>(o.revolution) == summary->scans;
  if (selected) {
    for (const LidarPoint& p : scan.points) writer->Write(p);
  }
  ++summary->scans;
}

/// The error of a run that wrote no point, naming the cause.
Status NoPointsError(const DecodeOptions& o, const PacketStream& stream, const DecodeSummary& s) {
  const std::string malformed =
      s.malformed == 0 ? "" : "; " + std::to_string(s.malformed) + " malformed (first: " + s.first_error + ")";
  if (s.points == 0 && !stream.saw_data()) return stream.NoDataError(o.input_path);
  if (s.points == 0 && s.packets == 0)
    return Status::Error(o.input_path + ": no decodable VLP-16 data packet" + malformed);
  if (s.points == 0)
    return Status::Error(o.input_path + ": " + std::to_string(s.packets) + " data packets gave 0 points inside " +
                         "the range limits [" + std::to_string(o.decoder.min_range_m) + ", " +
                         std::to_string(o.decoder.max_range_m) + "] m with return filter " +
                         FilterName(o.decoder.return_filter) + malformed);
  return Status::Error(o.input_path + ": revolution " + std::to_string(o.revolution) + " not found: the input has " +
                       std::to_string(s.scans) + " scans (0 .. " + std::to_string(s.scans - 1) + ")");
}

}  // namespace

bool DecodeOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = "decode: " + m;
    return false;
  };
  if (input_path.empty()) return fail("input_path is empty");
  if (output_prefix.empty()) return fail("output_prefix is empty");
  if (!std::isfinite(cut_azimuth_deg)) return fail("cut_azimuth_deg must be finite");
  if (revolution < -1) return fail("revolution must be >= -1");
  return decoder.Validate(error);
}

Status RunDecode(const DecodeOptions& o, DecodeSummary* summary) {
  *summary = DecodeSummary();
  std::string error;
  if (!o.Validate(&error)) return Status::Error(error);
  const Vlp16DecoderConfig& config = o.decoder;
  PacketStream stream;
  if (Status s = stream.Open(o); !s) return s;
  PointWriter writer;
  if (Status s = writer.Open(o.output_prefix); !s) return s;
  Vlp16Decoder decoder(LidarIntrinsics(), config);
  RevolutionSplitter splitter(o.cut_azimuth_deg);
  LidarPacket packet;
  Status status;
  std::vector<LidarPoint> points;
  for (std::size_t index = 0;; ++index) {
    Status bad;
    if (!stream.Next(&packet, &status)) {
      if (status) break;  // end of input
      bad = status;
    } else {
      points.clear();
      bad = decoder.Decode(packet, &points);
      if (!bad) bad.message = o.input_path + ": packet " + std::to_string(index) + ": " + bad.message;
    }
    if (!bad) {
      if (o.strict) return bad;
      if (summary->malformed++ == 0) summary->first_error = bad.message;
      continue;
    }
    const bool position =
        packet.udp_port == kVlp16PositionPort || packet.payload.size() == kVlp16PositionPacketBytes;
    ++(position ? summary->position_packets : summary->packets);
    if (points.empty()) continue;
    if (summary->points == 0) summary->t_first_s = points.front().t_s;
    summary->t_last_s = points.back().t_s;
    summary->points += points.size();
    for (const LidarPoint& p : points) {
      if (std::optional<LidarScan> scan = splitter.Add(p)) TakeScan(*scan, o, summary, &writer);
    }
  }
  if (std::optional<LidarScan> rest = splitter.Flush()) TakeScan(*rest, o, summary, &writer);
  summary->full_revolutions = splitter.crossings() > 1 ? splitter.crossings() - 1 : 0;
  summary->skipped_frames = stream.skipped();
  summary->points_written = writer.count();
  summary->merged_dual_duplicates = decoder.merged_dual_duplicates();
  if (Status s = writer.Finish(); !s) return s;
  if (summary->points_written == 0) return NoPointsError(o, stream, *summary);
  return WriteResolvedOptions(o);
}

bool ParseReturnFilter(const std::string& text, Vlp16ReturnFilter* filter) {
  if (text == "all") *filter = Vlp16ReturnFilter::kAll;
  else if (text == "strongest") *filter = Vlp16ReturnFilter::kStrongest;
  else if (text == "last") *filter = Vlp16ReturnFilter::kLast;
  else return false;
  return true;
}

void PrintDecodeSummary(const DecodeSummary& s, std::ostream& os) {
  os << "packets           " << s.packets << "\nposition packets  " << s.position_packets
     << "\nskipped frames    " << s.skipped_frames << "\nmalformed         " << s.malformed
     << (s.first_error.empty() ? "" : " (first: " + s.first_error + ")") << "\npoints            " << s.points
     << "\ndual duplicates   " << s.merged_dual_duplicates
     << " (points that stand for an echo both strongest and last: return 2)"
     << "\npoints written    " << s.points_written << "\nscans             " << s.scans
     << "\nfull revolutions  " << s.full_revolutions << "\ntime span         " << s.t_first_s << " .. "
     << s.t_last_s << " s (" << (s.t_last_s - s.t_first_s) << " s)\n";
}

}  // namespace rotolidar::bench
