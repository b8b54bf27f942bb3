#pragma once
// A bound IPv4 UDP socket for receiving sensor datagrams (VLP-16 packets, rig samples), with what a live input
// needs to see loss: a receive buffer sized for bursts and the kernel's own count of datagrams it dropped because
// that buffer was full (Linux SO_RXQ_OVFL; other systems report none). POSIX sockets; Linux first.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/util/status.hpp"

namespace rotolidar {

struct UdpSocketConfig {
  std::string bind_address = "0.0.0.0";  ///< dotted IPv4; "127.0.0.1" for loopback only
  uint16_t port = 0;                     ///< 0 = any free port (see UdpReceiveSocket::port())
  /// Requested kernel receive buffer [bytes]. 8 MiB holds ~5 s of VLP-16 data (~0.9 MB/s). The kernel caps the
  /// request at net.core.rmem_max unless the process may exceed it (root: SO_RCVBUFFORCE); rcvbuf_bytes() says
  /// what was granted. 0 keeps the system default (~208 KiB on Linux).
  std::size_t rcvbuf_bytes = 8u << 20;
  bool Validate(std::string* error) const;
};

/// Owns one socket. Not thread-safe: one reader thread (the sources below own theirs).
class UdpReceiveSocket {
 public:
  UdpReceiveSocket() = default;
  ~UdpReceiveSocket();
  UdpReceiveSocket(const UdpReceiveSocket&) = delete;
  UdpReceiveSocket& operator=(const UdpReceiveSocket&) = delete;

  /// Binds. Fails (message names address:port and the OS error) on a bad address, socket or bind error.
  Status Open(const UdpSocketConfig& config);
  /// Waits up to timeout_s for one datagram and copies at most `capacity` bytes of it into `buffer`. Returns its
  /// full size (> capacity: truncated), or -1 when none came in time or the socket is closed.
  long Receive(uint8_t* buffer, std::size_t capacity, double timeout_s);
  void Close();

  uint16_t port() const { return port_; }                  ///< the bound port
  std::size_t rcvbuf_bytes() const { return rcvbuf_; }     ///< the buffer the kernel granted [bytes]
  /// Datagrams the kernel dropped on this socket for lack of buffer space, as of the last Receive (Linux).
  uint64_t kernel_dropped() const { return kernel_dropped_; }
  bool is_open() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
  uint16_t port_ = 0;
  std::size_t rcvbuf_ = 0;
  uint64_t kernel_dropped_ = 0;
};

}  // namespace rotolidar
