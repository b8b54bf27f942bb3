// Live snapshots, status line and summary (contracts in live_outputs.hpp and live_session.hpp).
#include "bench/live/live_outputs.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "bench/run/atomic_write.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/io/trajectory_io.hpp"
#include "core/util/validation.hpp"

namespace rotolidar::bench {
double SteadyS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool LiveConfig::Validate(std::string* error) const {
  std::string why;
  if (!merge.Validate(&why)) return FailValidation(error, "merge." + why);
  if (max_pending_scans < 1) return FailValidation(error, "max_pending_scans: must be >= 1");
  if (!(snapshot_period_s >= 0.0)) return FailValidation(error, "snapshot_period_s: must be >= 0");
  if (!(status_period_s > 0.0)) return FailValidation(error, "status_period_s: must be > 0");
  if (!(idle_stop_s >= 0.0)) return FailValidation(error, "idle_stop_s: must be >= 0");
  if (!(duration_s >= 0.0)) return FailValidation(error, "duration_s: must be >= 0");
  if (rcvbuf_bytes > (std::size_t(1) << 30)) return FailValidation(error, "rcvbuf_bytes: more than 1 GiB");
  const bool distinct = (data_port == 0 || (data_port != position_port && data_port != rig_port)) &&
                        (position_port == 0 || position_port != rig_port);
  if (!distinct) return FailValidation(error, "data_port, position_port, rig_port: must differ (or be 0 = any free port)");
  return true;
}

std::string LiveStatus::Line() const {
  char line[400];
  std::snprintf(line, sizeof(line),
                "live %6.1f s | rig t %7.2f s | lidar %4.0f/s imu %4.0f/s enc %4.0f/s | inbox %zu | lost: net %zu "
                "rig %zu kernel %zu queue %zu bad %zu | scans %zu (%.1f/s, %.0f ms) dropped %zu | rss %.0f MB | ATE n/a%s%s",
                wall_s, rig_time_s, data_rate_hz, imu_rate_hz, encoder_rate_hz, queue_depth, packets_lost, rig_lost,
                kernel_dropped, queue_dropped, malformed, scans, scans_per_s, last_scan_ms, scans_dropped, peak_rss_mb,
                degenerate_axes.empty() ? "" : " | DEGENERATE: ", degenerate_axes.c_str());
  return line;
}

SnapshotWriter::SnapshotWriter(std::string out_dir, double period_s)
    : dir_(std::move(out_dir)), period_s_(period_s), last_s_(SteadyS()) {}

Status SnapshotWriter::Poll(const Estimator& estimator) {
  if (period_s_ <= 0.0) return Status::Ok();
  const double now = SteadyS();
  const std::size_t scans = estimator.trajectory().size();
  if (now - last_s_ < period_s_ || scans == last_scans_ || scans == 0) return Status::Ok();
  last_s_ = now;
  last_scans_ = scans;
  if (Status s = WriteAtomically(dir_ + "/trajectory.tum",
                                 [&](const std::string& part) {
                                   return WriteTrajectory(part, TrajectoryFormat::kTum, estimator.trajectory());
                                 });
      !s)
    return s;
  const std::vector<Eigen::Vector3d> map = estimator.map().Points();
  if (!map.empty()) {
    if (Status s = WriteAtomically(dir_ + "/map.ply", [&](const std::string& part) { return SavePointCloud(part, map); });
        !s)
      return s;
  }
  ++written_;
  return Status::Ok();
}

std::string DegenerateAxes(const DegeneracyRecord& degeneracy) {
  static const char* kAxes[6] = {"tx", "ty", "tz", "rx", "ry", "rz"};
  std::string out;
  if (!degeneracy.degenerate) return out;
  for (int i = 0; i < 6; ++i)
    if (degeneracy.axis_weight[i] > 0.5) out += (out.empty() ? "" : " ") + std::string(kAxes[i]);
  return out;
}

LiveStatus StatusRates::Update(LiveStatus status, double now_s) {
  if (have_ && now_s > last_s_) {
    const double dt = now_s - last_s_;
    data_hz_ = (status.data_packets - data_) / dt;
    imu_hz_ = (status.imu_samples - imu_) / dt;
    encoder_hz_ = (status.encoder_samples - encoder_) / dt;
    scans_hz_ = (status.scans - scans_) / dt;
  }
  have_ = true;
  last_s_ = now_s;
  data_ = status.data_packets;
  imu_ = status.imu_samples;
  encoder_ = status.encoder_samples;
  scans_ = status.scans;
  status.data_rate_hz = data_hz_;
  status.imu_rate_hz = imu_hz_;
  status.encoder_rate_hz = encoder_hz_;
  status.scans_per_s = scans_hz_;
  return status;
}

Status WriteLiveSummary(const std::string& path, const LiveStatus& s, const LiveConfig& c) {
  nlohmann::json j;
  j["wall_s"] = s.wall_s;
  j["rig_time_s"] = s.rig_time_s;
  j["received"] = {{"data_packets", s.data_packets}, {"position_packets", s.position_packets},
                   {"imu_samples", s.imu_samples}, {"encoder_samples", s.encoder_samples}};
  j["lost"] = {{"data_packets_from_timestamp_gaps", s.packets_lost}, {"rig_datagrams_from_sequence_gaps", s.rig_lost},
               {"kernel_dropped_datagrams", s.kernel_dropped}, {"queue_dropped", s.queue_dropped},
               {"malformed_datagrams", s.malformed}, {"late_samples", s.late_samples}};
  j["hold_timeouts"] = s.hold_timeouts;
  j["peak_rss_mb"] = s.peak_rss_mb;
  j["scans"] = {{"processed", s.scans}, {"dropped", s.scans_dropped}};
  j["config"] = {{"bind_address", c.bind_address}, {"data_port", c.data_port}, {"position_port", c.position_port},
                 {"rig_port", c.rig_port}, {"rcvbuf_bytes", c.rcvbuf_bytes}, {"hold_s", c.merge.hold_s},
                 {"max_pending_scans", c.max_pending_scans}, {"snapshot_period_s", c.snapshot_period_s},
                 {"status_period_s", c.status_period_s}, {"idle_stop_s", c.idle_stop_s},
                 {"duration_s", c.duration_s}};
  return WriteAtomically(path, [&](const std::string& part) {
    std::ofstream out(part);
    out << j.dump(2) << "\n";
    out.close();
    return out ? Status::Ok() : Status::Error(part + ": write failed");
  });
}

}  // namespace rotolidar::bench
