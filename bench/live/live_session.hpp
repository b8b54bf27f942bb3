#pragma once
// `rotolidar live`: SLAM from a rig's sensors as they send. Three UDP inputs (VLP-16 data and position packets,
// rig samples in the protocol of core/wire/rig_protocol.hpp), each read by its own thread into a bounded queue
// (core/wire/udp_source.hpp, rig_udp.hpp) that never waits for the estimator. The session's own thread puts
// the streams into time order (live_merger.hpp) and writes everything received into <out>/recording/ as it
// arrives, so any session can be replayed with `rotolidar slam` bit for bit. The estimator runs in a worker
// thread behind an inbox; when complete scans pile up (it cannot keep up) it drops the oldest whole scans and
// counts them. Every snapshot_period_s it writes trajectory.tum and map.ply (to a temporary name, then renamed:
// a reader never sees half a file); at the end the outputs of `rotolidar slam` (bench/run/slam_run.hpp) and
// live.json (the session's counters). Camera frames are not taken live yet.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "bench/live/live_merger.hpp"
#include "bench/run/slam_run.hpp"
#include "core/pipeline/estimator.hpp"
#include "core/types/calib.hpp"

namespace rotolidar::bench {

struct LiveConfig {
  std::string bind_address = "0.0.0.0";  ///< dotted IPv4 of the interface to listen on (all by default)
  uint16_t data_port = 2368;             ///< VLP-16 data packets (manual section 9); 0 = any free port
  uint16_t position_port = 8308;         ///< VLP-16 position packets; 0 = any free port
  uint16_t rig_port = 2370;              ///< rig samples (kRigSamplePort); 0 = any free port
  std::size_t rcvbuf_bytes = 8u << 20;   ///< kernel receive buffer per socket [bytes]
  LiveMergerConfig merge;
  /// Behind: one inbox batch spans more revolutions than this. The oldest complete scans are then dropped, the
  /// newest kept; otherwise every packet is processed as `rotolidar slam` processes a recording.
  std::size_t max_pending_scans = 3;
  double snapshot_period_s = 10.0;  ///< wall time between trajectory / map snapshots [s]; 0 = none
  double status_period_s = 1.0;     ///< wall time between status reports [s]
  double idle_stop_s = 0.0;         ///< stop when no input came for this long after the first [s]; 0 = never
  double duration_s = 0.0;          ///< stop after this much wall time [s]; 0 = only on request
  bool Validate(std::string* error) const;
};

/// What the session has seen so far (counters are totals since Start; rates over the last status period).
struct LiveStatus {
  double wall_s = 0.0;             ///< since Start
  double rig_time_s = 0.0;         ///< of the newest packet fed to the estimator
  std::size_t data_packets = 0, position_packets = 0, imu_samples = 0, encoder_samples = 0;
  double data_rate_hz = 0.0, imu_rate_hz = 0.0, encoder_rate_hz = 0.0;
  std::size_t queue_depth = 0;     ///< items in the estimator's inbox
  std::size_t kernel_dropped = 0;  ///< datagrams the kernel dropped (all sockets)
  std::size_t queue_dropped = 0;   ///< datagrams / samples lost to a full receive queue
  std::size_t packets_lost = 0;    ///< data packets missing from the timestamp sequence
  std::size_t rig_lost = 0;        ///< rig datagrams missing from their sequence numbers
  std::size_t malformed = 0;       ///< datagrams of a wrong size or that did not decode
  std::size_t late_samples = 0, hold_timeouts = 0;
  std::size_t scans = 0, scans_dropped = 0, pending_scans = 0;
  double scans_per_s = 0.0, last_scan_ms = 0.0;
  double peak_rss_mb = 0.0;        ///< the process's peak resident memory so far [MiB] (getrusage)
  std::string degenerate_axes;     ///< of the last scan, e.g. "tx ry" (empty when well observed)
  std::string Line() const;        ///< one status line for a terminal
};

class LiveSession {
 public:
  /// calib must be valid and config must Validate (checked by Start).
  LiveSession(const RigCalib& calib, const EstimatorConfig& estimator, const LiveConfig& config,
              const std::string& out_dir);
  ~LiveSession();

  /// Binds the three sockets and creates <out_dir>/recording. Fails naming the port or folder.
  Status Start();
  uint16_t data_port() const;
  uint16_t position_port() const;
  uint16_t rig_port() const;

  /// Runs until *stop is set (a signal handler), duration_s or idle_stop_s; calls on_status every
  /// status_period_s. Then stops the readers, feeds what they hold, finishes the estimator and writes the
  /// outputs. The returned status is the first write error, if any.
  Status Run(const std::atomic<bool>& stop, const std::function<void(const LiveStatus&)>& on_status);

  /// The counters now: from the thread that calls Run (its on_status gets the same), or after Run.
  LiveStatus status() const;
  const SlamRunResult& result() const;  ///< valid after Run

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rotolidar::bench
