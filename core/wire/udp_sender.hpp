#pragma once
// Sending VLP-16 packets over UDP as the sensor would (a fake sensor for replay, demos and tests): data packets to
// one port, position packets to another, paced at N x real time from their capture times. IPv4 only.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/types/messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

struct UdpSenderConfig {
  std::string host = "127.0.0.1";  ///< dotted IPv4 destination; loopback by default ("255.255.255.255" broadcasts)
  uint16_t data_port = 2368;       ///< destination of 1206-byte data packets (the sensor's default)
  uint16_t position_port = 8308;   ///< destination of packets whose udp_port is 8308 (the sensor's default)
  /// True when usable; otherwise false with the field named in *error.
  bool Validate(std::string* error) const;
};

/// Wall-clock pacing of a packet stream at `rate` x real time: the first packet given to WaitUntilDue leaves at
/// once, packet i when (t_capture_s[i] - t_capture_s[0]) / rate seconds of the steady clock have passed since.
/// Deadlines are absolute, so oversleeping one packet does not slow the average rate. Capture times that go
/// backwards are due at once. rate <= 0 never waits. Not thread-safe.
class PacketPacer {
 public:
  explicit PacketPacer(double rate) : rate_(rate) {}

  /// Seconds after the first packet that a packet captured at t_capture_s is due (0 before the first call, or
  /// when rate <= 0). Pure: no clock involved.
  double DueAfterFirstS(Seconds t_capture_s) const;
  /// Sleeps until the packet is due; returns how late it is after waking [s] (>= 0; the OS wakes late).
  double WaitUntilDue(Seconds t_capture_s);
  double max_lateness_s() const { return max_lateness_s_; }
  /// Wall time since the first packet [s] (0 before it).
  double ElapsedS() const;

 private:
  double rate_;
  bool started_ = false;
  Seconds t0_s_ = 0.0;
  std::chrono::steady_clock::time_point wall0_;
  double max_lateness_s_ = 0.0;
};

/// Sends LidarPackets' payloads as UDP datagrams. A packet with udp_port 8308 goes to the position port, every
/// other packet to the data port. Not thread-safe; closes its socket on destruction.
class UdpPacketSender {
 public:
  UdpPacketSender() = default;
  ~UdpPacketSender();
  UdpPacketSender(const UdpPacketSender&) = delete;
  UdpPacketSender& operator=(const UdpPacketSender&) = delete;

  /// Opens the socket. Fails (message names the field or host) on a bad config or a socket error.
  Status Open(const UdpSenderConfig& config);
  /// Every packet to host:port, whatever its udp_port.
  Status Open(const std::string& host, uint16_t port);
  /// Fails before Open, or when the kernel does not take the whole datagram (message names host:port).
  Status Send(const LidarPacket& packet);
  /// Sends all packets in order, paced by a PacketPacer at `rate` x real time (<= 0: as fast as possible).
  /// Stops at the first send error (message names the packet index).
  Status SendAll(const std::vector<LidarPacket>& packets, double rate);
  void Close();

  std::size_t sent() const { return sent_; }  ///< datagrams sent since Open
  const UdpSenderConfig& config() const { return config_; }

 private:
  int fd_ = -1;
  UdpSenderConfig config_;
  std::size_t sent_ = 0;
};

}  // namespace rotolidar
