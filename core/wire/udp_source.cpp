// UDP receive/send of VLP-16 packets with POSIX sockets (contract in udp_source.hpp).
#include "core/wire/udp_source.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>

#include "core/wire/vlp16.hpp"

namespace rotolidar {
namespace {

double SteadyNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool MakeAddress(const std::string& host, uint16_t port, sockaddr_in* addr) {
  std::memset(addr, 0, sizeof(*addr));
  addr->sin_family = AF_INET;
  addr->sin_port = htons(port);
  return inet_pton(AF_INET, host.c_str(), &addr->sin_addr) == 1;
}

std::string Where(const std::string& host, uint16_t port) { return host + ":" + std::to_string(port); }

}  // namespace

bool UdpSourceConfig::Validate(std::string* error) const {
  if (queue_capacity == 0) {
    if (error) *error = "UdpSourceConfig: queue_capacity must be >= 1";
    return false;
  }
  if (!std::isfinite(rig_time_at_start_s)) {
    if (error) *error = "UdpSourceConfig: rig_time_at_start_s must be finite";
    return false;
  }
  return true;
}

UdpPacketSource::~UdpPacketSource() { Stop(); }

Status UdpPacketSource::Start(const UdpSourceConfig& config) {
  std::string error;
  if (!config.Validate(&error)) return Status::Error(error);
  if (fd_ >= 0 || running_) return Status::Error("UdpPacketSource: already started");
  sockaddr_in addr;
  const std::string where = Where(config.bind_address, config.port);
  if (!MakeAddress(config.bind_address, config.port, &addr)) {
    return Status::Error("UdpPacketSource: bad IPv4 address '" + config.bind_address + "'");
  }
  fd_ = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) return Status::Error("UdpPacketSource: socket(): " + std::string(std::strerror(errno)));
  const int one = 1;
  setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  if (bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    const std::string err = std::strerror(errno);
    close(fd_);
    fd_ = -1;
    return Status::Error("UdpPacketSource: bind " + where + ": " + err);
  }
  socklen_t len = sizeof(addr);
  getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  bound_port_ = ntohs(addr.sin_port);
  config_ = config;
  start_steady_s_ = SteadyNowS();
  running_ = true;
  thread_ = std::thread(&UdpPacketSource::ReceiveLoop, this);
  return Status::Ok();
}

void UdpPacketSource::ReceiveLoop() {
  std::vector<uint8_t> buffer(65536);
  while (running_) {
    pollfd pfd{fd_, POLLIN, 0};
    if (poll(&pfd, 1, 20) <= 0) continue;  // 20 ms: how long Stop may wait for the thread
    const ssize_t n = recv(fd_, buffer.data(), buffer.size(), 0);
    if (n < 0) continue;
    LidarPacket packet;
    packet.t_capture_s = config_.rig_time_at_start_s + (SteadyNowS() - start_steady_s_);
    if (static_cast<std::size_t>(n) == kVlp16PacketBytes) {
      packet.udp_port = kVlp16DataPort;
    } else if (static_cast<std::size_t>(n) == kVlp16PositionPacketBytes) {
      packet.udp_port = kVlp16PositionPort;
    } else {
      ++rejected_;
      continue;
    }
    packet.payload.assign(buffer.begin(), buffer.begin() + n);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (queue_.size() >= config_.queue_capacity) {
        ++dropped_;
        continue;
      }
      queue_.push_back(std::move(packet));
      ++received_;
    }
    cv_.notify_one();
  }
}

bool UdpPacketSource::Pop(LidarPacket* packet, double timeout_s) {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto timeout = std::chrono::duration<double>(std::max(0.0, timeout_s));
  cv_.wait_for(lock, timeout, [&] { return !queue_.empty() || !running_; });
  if (queue_.empty()) return false;
  *packet = std::move(queue_.front());
  queue_.pop_front();
  return true;
}

void UdpPacketSource::Stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  cv_.notify_all();
}

}  // namespace rotolidar
