#pragma once
// What `rotolidar live` writes while it runs and when it stops, beside the outputs of `rotolidar slam`:
//   trajectory.tum, map.ply   snapshots every snapshot_period_s of wall time (temporary name + rename), replaced
//                             by the final outputs at the end
//   live.json                 the session's counters (LiveStatus) and its resolved live configuration
#include <string>

#include "bench/live/live_session.hpp"
#include "core/pipeline/estimator.hpp"

namespace rotolidar::bench {

/// Seconds on the monotonic clock (the host's std::chrono::steady_clock): for periods and rates, not stamps.
double SteadyS();

class SnapshotWriter {
 public:
  /// period_s <= 0: never writes.
  SnapshotWriter(std::string out_dir, double period_s);
  /// Writes trajectory.tum and map.ply when period_s of wall time passed since the last snapshot and a new scan
  /// came. Fails naming the file (the caller keeps running).
  Status Poll(const Estimator& estimator);
  std::size_t written() const { return written_; }

 private:
  std::string dir_;
  double period_s_;
  double last_s_;
  std::size_t last_scans_ = 0, written_ = 0;
};

/// "tx ry" for the axes of a degenerate scan (axis_weight > 0.5), empty when it is well observed.
std::string DegenerateAxes(const DegeneracyRecord& degeneracy);

/// Turns totals into per-second rates between consecutive calls.
class StatusRates {
 public:
  LiveStatus Update(LiveStatus status, double now_s);

 private:
  bool have_ = false;
  double last_s_ = 0.0;
  std::size_t data_ = 0, imu_ = 0, encoder_ = 0, scans_ = 0;
  double data_hz_ = 0.0, imu_hz_ = 0.0, encoder_hz_ = 0.0, scans_hz_ = 0.0;
};

/// live.json. Fails naming the file.
Status WriteLiveSummary(const std::string& path, const LiveStatus& status, const LiveConfig& config);

}  // namespace rotolidar::bench
