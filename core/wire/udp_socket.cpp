// UDP receive socket with kernel drop counts (contract in udp_socket.hpp).
#include "core/wire/udp_socket.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>

namespace rotolidar {

bool UdpSocketConfig::Validate(std::string* error) const {
  in_addr addr;
  if (inet_pton(AF_INET, bind_address.c_str(), &addr) != 1) {
    if (error) *error = "bind_address: '" + bind_address + "' is not a dotted IPv4 address";
    return false;
  }
  if (rcvbuf_bytes > (std::size_t(1) << 30)) {
    if (error) *error = "rcvbuf_bytes: " + std::to_string(rcvbuf_bytes) + " is more than 1 GiB";
    return false;
  }
  return true;
}

UdpReceiveSocket::~UdpReceiveSocket() { Close(); }

Status UdpReceiveSocket::Open(const UdpSocketConfig& config) {
  std::string error;
  if (!config.Validate(&error)) return Status::Error("udp socket: " + error);
  if (fd_ >= 0) return Status::Error("udp socket: already open");
  const std::string where = config.bind_address + ":" + std::to_string(config.port);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(config.port);
  inet_pton(AF_INET, config.bind_address.c_str(), &addr.sin_addr);
  fd_ = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) return Status::Error("udp socket " + where + ": socket(): " + std::strerror(errno));
  const int one = 1;
  setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
#ifdef SO_RXQ_OVFL
  setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof(one));
#endif
  if (config.rcvbuf_bytes > 0) {
    const int want = static_cast<int>(config.rcvbuf_bytes);
#ifdef SO_RCVBUFFORCE
    if (setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &want, sizeof(want)) != 0)  // needs CAP_NET_ADMIN
#endif
      setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &want, sizeof(want));  // capped at net.core.rmem_max
  }
  int granted = 0;
  socklen_t glen = sizeof(granted);
  getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &granted, &glen);
  rcvbuf_ = granted > 0 ? static_cast<std::size_t>(granted) : 0;
  if (bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    const std::string err = std::strerror(errno);
    Close();
    return Status::Error("udp socket: bind " + where + ": " + err);
  }
  socklen_t len = sizeof(addr);
  getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  return Status::Ok();
}

long UdpReceiveSocket::Receive(uint8_t* buffer, std::size_t capacity, double timeout_s) {
  if (fd_ < 0) return -1;
  pollfd pfd{fd_, POLLIN, 0};
  const int timeout_ms = static_cast<int>(std::ceil(std::max(0.0, timeout_s) * 1e3));
  if (poll(&pfd, 1, timeout_ms) <= 0) return -1;
  iovec iov{buffer, capacity};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(uint32_t))];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof(control);
  const ssize_t n = recvmsg(fd_, &msg, MSG_TRUNC);
  if (n < 0) return -1;
#ifdef SO_RXQ_OVFL
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      uint32_t dropped = 0;  // the socket's running total since it was opened
      std::memcpy(&dropped, CMSG_DATA(c), sizeof(dropped));
      kernel_dropped_ = dropped;
    }
  }
#endif
  return static_cast<long>(n);
}

void UdpReceiveSocket::Close() {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
}

}  // namespace rotolidar
