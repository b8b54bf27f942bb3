#pragma once
// Rig samples (IMU, encoder) over UDP with the rig-sample protocol (rig_protocol.hpp): a receiver with a bounded
// queue for a live estimator, and a sender (a fake rig for replay and tests; the reference for firmware). IPv4.
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/wire/rig_protocol.hpp"
#include "core/wire/udp_socket.hpp"

namespace rotolidar {

struct RigSourceConfig {
  UdpSocketConfig socket;  ///< port 0 = any free port (RigSampleSource::port())
  std::size_t queue_capacity = 65536;  ///< samples; ~50 s of a 200 Hz IMU + 1 kHz encoder
  bool Validate(std::string* error) const;
};

/// Receives rig datagrams in a background thread into a bounded FIFO of samples, in arrival order. Counts what
/// goes wrong: datagrams that do not decode (malformed; the last message is kept), samples dropped on a full queue
/// (the NEW ones), datagrams lost on the way (sequence gaps), datagrams that came late or twice (sequence steps
/// back; their samples are still queued: the consumer orders by time), and the kernel's buffer drops.
/// Pop/Stop/counters are thread-safe; Start once per object.
class RigSampleSource {
 public:
  RigSampleSource() = default;
  ~RigSampleSource();
  RigSampleSource(const RigSampleSource&) = delete;
  RigSampleSource& operator=(const RigSampleSource&) = delete;

  /// Binds and starts the receiver. Fails (message names address and port) on a bad config or a bind error.
  Status Start(const RigSourceConfig& config);
  /// Moves every queued sample into *out (appended); waits up to timeout_s when none is queued.
  /// Returns how many were appended.
  std::size_t PopAll(std::vector<RigSample>* out, double timeout_s);
  void Stop();  ///< Idempotent; queued samples stay poppable.

  uint16_t port() const { return port_; }
  std::size_t datagrams() const { return datagrams_; }   ///< decoded datagrams
  std::size_t samples() const { return samples_; }       ///< samples queued
  std::size_t malformed() const { return malformed_; }
  std::size_t dropped() const { return dropped_; }       ///< samples lost to a full queue
  std::size_t lost() const { return lost_; }             ///< datagrams missing from the sequence
  std::size_t out_of_order() const { return out_of_order_; }
  std::size_t kernel_dropped() const { return kernel_dropped_; }
  std::string last_error() const;  ///< the last malformed datagram's message (empty when none)

 private:
  void ReceiveLoop();
  void CountSequence(uint32_t sequence);

  RigSourceConfig config_;
  UdpReceiveSocket socket_;
  uint16_t port_ = 0;
  std::thread thread_;
  std::atomic<bool> running_{false};
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<RigSample> queue_;
  std::string last_error_;
  bool have_sequence_ = false;  // receiver thread only
  uint32_t next_sequence_ = 0;
  std::atomic<std::size_t> datagrams_{0}, samples_{0}, malformed_{0}, dropped_{0}, lost_{0}, out_of_order_{0},
      kernel_dropped_{0};
};

/// Sends samples in datagrams of up to `batch` records with consecutive sequence numbers. Not thread-safe.
class RigSampleSender {
 public:
  RigSampleSender() = default;
  ~RigSampleSender();
  RigSampleSender(const RigSampleSender&) = delete;
  RigSampleSender& operator=(const RigSampleSender&) = delete;

  /// Opens a socket towards host:port. Fails naming the host on a bad address or a socket error.
  Status Open(const std::string& host, uint16_t port);
  /// Queues a sample; sends a datagram when `batch` samples are queued.
  Status Add(const RigSample& sample, std::size_t batch = 1);
  Status Flush();  ///< sends what is queued (nothing when empty)
  void Close();
  std::size_t datagrams_sent() const { return sequence_; }

 private:
  int fd_ = -1;
  std::vector<uint8_t> address_;  // sockaddr_in bytes
  RigDatagram pending_;
  uint32_t sequence_ = 0;
  std::vector<uint8_t> bytes_;
};

}  // namespace rotolidar
