#pragma once
// Live VLP-16 packets over UDP: a receiver with a bounded queue (the estimator's input from a real sensor). The
// sender that plays packets back (a fake sensor) is in udp_sender.hpp, included here for its users. IPv4 only.
// Loss is counted where it happens: a full queue (dropped), a full kernel buffer (kernel_dropped) and packets
// that never arrived (lost: gaps in the data packets' timestamps, core/wire/packet_gaps.hpp).
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/wire/packet_gaps.hpp"
#include "core/wire/udp_sender.hpp"
#include "core/wire/udp_socket.hpp"
#include "core/types/messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

struct UdpSourceConfig {
  std::string bind_address = "0.0.0.0";  ///< "127.0.0.1" for loopback only
  uint16_t port = 2368;                  ///< 0 = any free port (see UdpPacketSource::port())
  std::size_t queue_capacity = 4096;     ///< packets; ~5 s of single-return data
  double rig_time_at_start_s = 0.0;      ///< t_capture_s of a packet = this + seconds since Start (steady clock)
  std::size_t rcvbuf_bytes = 8u << 20;   ///< kernel receive buffer [bytes] (UdpSocketConfig::rcvbuf_bytes)
  bool Validate(std::string* error) const;
};

/// Receives datagrams on one port in a background thread into a bounded FIFO. When the queue is full the NEW
/// datagram is dropped and counted (the queue keeps its order). Datagrams of 1206 bytes become data packets
/// (udp_port 2368), of 512 bytes position packets (8308), whatever port they came to; other sizes are counted as
/// rejected. Pop/Stop/counters are thread-safe; Start once per object.
class UdpPacketSource {
 public:
  UdpPacketSource() = default;
  ~UdpPacketSource();
  UdpPacketSource(const UdpPacketSource&) = delete;
  UdpPacketSource& operator=(const UdpPacketSource&) = delete;

  /// Binds and starts the receiver thread. Fails (message names address and port) on a bad config, an
  /// unparsable address or a bind error.
  Status Start(const UdpSourceConfig& config);
  /// Waits up to timeout_s for a packet; false when none came (or the source is stopped and empty).
  bool Pop(LidarPacket* packet, double timeout_s);
  /// Stops and joins the receiver; queued packets stay poppable. Idempotent.
  void Stop();

  uint16_t port() const { return bound_port_; }  ///< the bound port (useful with config.port = 0)
  std::size_t received() const { return received_; }  ///< datagrams accepted into the queue
  std::size_t dropped() const { return dropped_; }    ///< datagrams lost to a full queue
  std::size_t rejected() const { return rejected_; }  ///< datagrams of the wrong size
  /// Datagrams the kernel dropped before this source could read them (socket buffer full; Linux only).
  std::size_t kernel_dropped() const { return kernel_dropped_; }
  /// Data packets that never arrived, from the gaps in their timestamps (network loss, upstream drops).
  std::size_t lost() const { return lost_; }
  std::size_t rcvbuf_bytes() const { return rcvbuf_granted_; }  ///< the receive buffer the kernel granted

 private:
  void ReceiveLoop();

  UdpSourceConfig config_;
  UdpReceiveSocket socket_;
  Vlp16GapCounter gaps_;  // receiver thread only
  uint16_t bound_port_ = 0;
  std::size_t rcvbuf_granted_ = 0;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<LidarPacket> queue_;
  std::atomic<std::size_t> received_{0}, dropped_{0}, rejected_{0}, kernel_dropped_{0}, lost_{0};
  double start_steady_s_ = 0.0;
};

}  // namespace rotolidar
