// The live session's threads (contract in live_session.hpp).
#include "bench/live/live_session.hpp"

#include <sys/resource.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "bench/live/live_outputs.hpp"
#include "core/io/recording.hpp"
#include "core/util/log.hpp"
#include "core/wire/rig_udp.hpp"
#include "core/wire/udp_source.hpp"

namespace rotolidar::bench {
struct LiveSession::Impl {
  RigCalib calib;
  EstimatorConfig estimator_config;
  LiveConfig config;
  std::string out_dir;
  UdpPacketSource data, position;
  RigSampleSource rig;
  LiveMerger merger{LiveMergerConfig{}};
  RecordingWriter recording;
  double t0_s = 0.0;

  // The estimator's inbox (session thread -> worker).
  mutable std::mutex mutex;
  std::condition_variable cv;
  std::deque<LiveItem> inbox;
  bool inbox_closed = false;

  // Written by the worker, read by status() under `mutex`.
  LiveStatus worker_view;
  SlamRunResult result;
  Status worker_status = Status::Ok();

  Status OpenSources();
  std::size_t Drain(double wait_s);
  void Worker();
  void FeedAll(std::deque<LiveItem>* items, Estimator* estimator, SnapshotWriter* snapshots);
  void AfterScans(std::vector<ScanReport> reports, Estimator* estimator, SnapshotWriter* snapshots);
  LiveStatus Current() const;
  void Forward(std::vector<LiveItem> items);
};

Status LiveSession::Impl::OpenSources() {
  UdpSourceConfig lidar;
  lidar.bind_address = config.bind_address;
  lidar.rcvbuf_bytes = config.rcvbuf_bytes;
  lidar.rig_time_at_start_s = SteadyS();  // packets are stamped with the host's steady clock; the merger maps it
  lidar.port = config.data_port;
  if (Status s = data.Start(lidar); !s) return Status::Error("live: data packets: " + s.message);
  lidar.port = config.position_port;
  lidar.queue_capacity = 256;
  lidar.rig_time_at_start_s = SteadyS();
  if (Status s = position.Start(lidar); !s) return Status::Error("live: position packets: " + s.message);
  RigSourceConfig samples;
  samples.socket.bind_address = config.bind_address;
  samples.socket.port = config.rig_port;
  samples.socket.rcvbuf_bytes = config.rcvbuf_bytes;
  if (Status s = rig.Start(samples); !s) return Status::Error("live: rig samples: " + s.message);
  return Status::Ok();
}

// Moves what the readers hold through the merger into the recording and the inbox; returns the items released.
std::size_t LiveSession::Impl::Drain(double wait_s) {
  std::vector<RigSample> samples;
  rig.PopAll(&samples, wait_s);
  for (const RigSample& s : samples) merger.AddSample(s);
  LidarPacket packet;
  while (data.Pop(&packet, 0.0)) merger.AddPacket(std::move(packet));
  while (position.Pop(&packet, 0.0)) merger.AddPacket(std::move(packet));
  std::vector<LiveItem> items;
  merger.Release(SteadyS(), &items);
  const std::size_t n = items.size();
  Forward(std::move(items));
  return n;
}

// Writes items into the recording and hands them to the worker.
void LiveSession::Impl::Forward(std::vector<LiveItem> items) {
  for (const LiveItem& item : items) {
    rotolidar::Status s = rotolidar::Status::Ok();
    if (item.kind == LiveItem::Kind::kPacket) s = recording.Write(item.packet);
    else if (item.kind == LiveItem::Kind::kImu) s = recording.Write(item.imu);
    else s = recording.Write(item.encoder);
    if (!s) LOG_WARN("live: recording: " << s.message);
  }
  if (!items.empty()) {
    std::lock_guard<std::mutex> lock(mutex);
    for (LiveItem& item : items) inbox.push_back(std::move(item));
  }
  cv.notify_one();
}

// Keeping up (the batch spans at most max_pending_scans revolutions): Process after every packet, exactly as
// `rotolidar slam` plays a recording, so that the session equals an offline run of its own recording. Behind:
// feed the whole batch (decoding is cheap), drop the oldest complete revolutions, keep the newest.
void LiveSession::Impl::FeedAll(std::deque<LiveItem>* items, Estimator* estimator, SnapshotWriter* snapshots) {
  double first_s = 0.0, last_s = 0.0;
  bool any = false;
  for (const LiveItem& item : *items) {
    if (item.kind != LiveItem::Kind::kPacket) continue;
    if (!any) first_s = item.packet.t_capture_s;
    last_s = item.packet.t_capture_s;
    any = true;
  }
  const bool behind = last_s - first_s > config.max_pending_scans * 60.0 / calib.lidar.rpm;
  for (const LiveItem& item : *items) {
    switch (item.kind) {
      case LiveItem::Kind::kImu: estimator->Feed(item.imu); break;
      case LiveItem::Kind::kEncoder: estimator->Feed(item.encoder); break;
      default:
        if (Status s = estimator->Feed(item.packet); !s) LOG_WARN("live: packet: " << s.message);
        if (!behind) AfterScans(estimator->Process(), estimator, snapshots);
    }
  }
  if (behind && estimator->pending_scans() > 1) {
    const std::size_t dropped = estimator->DropPendingScans(1);
    std::lock_guard<std::mutex> lock(mutex);
    worker_view.scans_dropped += dropped;
  }
  if (any) {
    std::lock_guard<std::mutex> lock(mutex);
    worker_view.rig_time_s = last_s;
  }
  items->clear();
}

void LiveSession::Impl::AfterScans(std::vector<ScanReport> reports, Estimator* estimator,
                                   SnapshotWriter* snapshots) {
  std::lock_guard<std::mutex> lock(mutex);
  for (ScanReport& r : reports) {
    worker_view.last_scan_ms = r.timings.total_ms;
    worker_view.degenerate_axes = DegenerateAxes(r.degeneracy);
    ++worker_view.scans;
    r.deskew_source = {};
    r.deskewed_base = {};
    result.scans.push_back(std::move(r));
  }
  worker_view.pending_scans = estimator->pending_scans();
  if (Status s = snapshots->Poll(*estimator); !s && worker_status) worker_status = s;
}

void LiveSession::Impl::Worker() {
  Estimator estimator(calib, estimator_config);
  SnapshotWriter snapshots(out_dir, config.snapshot_period_s);
  std::deque<LiveItem> items;
  while (true) {
    {
      std::unique_lock<std::mutex> lock(mutex);
      cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return !inbox.empty() || inbox_closed; });
      if (inbox.empty() && inbox_closed) break;
      items.swap(inbox);
    }
    FeedAll(&items, &estimator, &snapshots);
    AfterScans(estimator.Process(), &estimator, &snapshots);
  }
  AfterScans(estimator.Finish(), &estimator, &snapshots);
  std::lock_guard<std::mutex> lock(mutex);
  result.trajectory = result.odometry_trajectory = estimator.trajectory();
  result.map_points = estimator.map().NumPoints();
  result.bad_packets = estimator.bad_packets();
  result.packet_order = estimator.packet_order_counts();
  if (!result.scans.empty()) result.data_duration_s = result.scans.back().t_end_s - result.scans.front().t_start_s;
  if (result.trajectory.empty()) {
    if (worker_status) worker_status = Status::Error("live: no complete LiDAR revolution was received");
    return;
  }
  if (Status s = WriteSlamOutputs(out_dir, estimator, result); !s && worker_status) worker_status = s;
}

LiveStatus LiveSession::Impl::Current() const {
  LiveStatus st;
  {
    std::lock_guard<std::mutex> lock(mutex);
    st = worker_view;
    st.queue_depth = inbox.size();
  }
  st.wall_s = SteadyS() - t0_s;
  st.data_packets = data.received();
  st.position_packets = position.received();
  st.imu_samples = merger.counts().imu;
  st.encoder_samples = merger.counts().encoder;
  st.kernel_dropped = data.kernel_dropped() + position.kernel_dropped() + rig.kernel_dropped();
  st.queue_dropped = data.dropped() + position.dropped() + rig.dropped();
  st.packets_lost = data.lost();
  st.rig_lost = rig.lost();
  st.malformed = data.rejected() + position.rejected() + rig.malformed();
  st.late_samples = merger.counts().late_samples;
  st.hold_timeouts = merger.counts().hold_timeouts;
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) == 0) st.peak_rss_mb = usage.ru_maxrss / 1024.0;  // Linux: KiB
  return st;
}

LiveSession::LiveSession(const RigCalib& calib, const EstimatorConfig& estimator, const LiveConfig& config,
                         const std::string& out_dir)
    : impl_(std::make_unique<Impl>()) {
  impl_->calib = calib;
  impl_->estimator_config = estimator;
  impl_->config = config;
  impl_->out_dir = out_dir;
}

LiveSession::~LiveSession() {
  impl_->data.Stop();
  impl_->position.Stop();
  impl_->rig.Stop();
}

Status LiveSession::Start() {
  std::string why;
  if (!impl_->config.Validate(&why)) return Status::Error("live config: " + why);
  if (!impl_->estimator_config.Validate(&why)) return Status::Error("slam config: " + why);
  impl_->config.merge.lidar_clock_offset_s = impl_->calib.lidar_clock_offset_s;
  impl_->config.merge.min_capture_s = -impl_->calib.epoch_unix_s;
  impl_->merger = LiveMerger(impl_->config.merge);
  if (Status s = impl_->recording.Open(impl_->out_dir + "/recording", impl_->calib); !s) return s;
  impl_->t0_s = SteadyS();
  return impl_->OpenSources();
}

uint16_t LiveSession::data_port() const { return impl_->data.port(); }
uint16_t LiveSession::position_port() const { return impl_->position.port(); }
uint16_t LiveSession::rig_port() const { return impl_->rig.port(); }
LiveStatus LiveSession::status() const { return impl_->Current(); }
const SlamRunResult& LiveSession::result() const { return impl_->result; }

Status LiveSession::Run(const std::atomic<bool>& stop, const std::function<void(const LiveStatus&)>& on_status) {
  Impl& m = *impl_;
  std::thread worker(&Impl::Worker, &m);
  StatusRates rates;
  double next_status = m.t0_s + m.config.status_period_s, last_input = 0.0;
  while (!stop) {
    const double now = SteadyS();
    if (m.Drain(0.01) > 0) last_input = now;
    if (m.config.duration_s > 0.0 && now - m.t0_s >= m.config.duration_s) break;
    if (m.config.idle_stop_s > 0.0 && last_input > 0.0 && now - last_input >= m.config.idle_stop_s) break;
    if (now >= next_status && on_status) {
      on_status(rates.Update(m.Current(), now));
      next_status += m.config.status_period_s;
    }
  }
  m.data.Stop();  // queued datagrams stay poppable
  m.position.Stop();
  m.rig.Stop();
  m.Drain(0.0);
  std::vector<LiveItem> rest;
  m.merger.ReleaseAll(&rest);
  m.Forward(std::move(rest));
  {
    std::lock_guard<std::mutex> lock(m.mutex);
    m.inbox_closed = true;
  }
  m.cv.notify_one();
  worker.join();
  const Status closed = m.recording.Close();
  const LiveStatus final_status = m.Current();
  if (on_status) on_status(final_status);
  const Status summary = WriteLiveSummary(m.out_dir + "/live.json", final_status, m.config);
  if (!m.worker_status) return m.worker_status;
  if (!closed) return closed;
  return summary;
}

}  // namespace rotolidar::bench
