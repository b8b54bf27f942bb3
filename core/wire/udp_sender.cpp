// Paced UDP sending of VLP-16 packets with POSIX sockets (contract in udp_sender.hpp).
#include "core/wire/udp_sender.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <thread>

namespace rotolidar {
namespace {

constexpr uint16_t kPositionPort = 8308;  // LidarPacket::udp_port of a position packet (kVlp16PositionPort)

bool MakeAddress(const std::string& host, uint16_t port, sockaddr_in* addr) {
  std::memset(addr, 0, sizeof(*addr));
  addr->sin_family = AF_INET;
  addr->sin_port = htons(port);
  return inet_pton(AF_INET, host.c_str(), &addr->sin_addr) == 1;
}

}  // namespace

bool UdpSenderConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = "UdpSenderConfig: " + m;
    return false;
  };
  sockaddr_in addr;
  if (!MakeAddress(host, data_port, &addr)) return fail("host '" + host + "' is not a dotted IPv4 address");
  if (data_port == 0) return fail("data_port must be 1..65535");
  if (position_port == 0) return fail("position_port must be 1..65535");
  return true;
}

// ---------------------------------------------------------------------------------------------------------------
double PacketPacer::DueAfterFirstS(Seconds t_capture_s) const {
  if (!started_ || rate_ <= 0.0) return 0.0;
  return std::max(0.0, (t_capture_s - t0_s_) / rate_);
}

double PacketPacer::WaitUntilDue(Seconds t_capture_s) {
  if (!started_) {
    started_ = true;
    t0_s_ = t_capture_s;
    wall0_ = std::chrono::steady_clock::now();
    return 0.0;
  }
  if (rate_ <= 0.0) return 0.0;
  const auto due = wall0_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(DueAfterFirstS(t_capture_s)));
  std::this_thread::sleep_until(due);
  const double late_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - due).count();
  max_lateness_s_ = std::max(max_lateness_s_, late_s);
  return std::max(0.0, late_s);
}

double PacketPacer::ElapsedS() const {
  if (!started_) return 0.0;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
}

// ---------------------------------------------------------------------------------------------------------------
UdpPacketSender::~UdpPacketSender() { Close(); }

Status UdpPacketSender::Open(const UdpSenderConfig& config) {
  Close();
  std::string error;
  if (!config.Validate(&error)) return Status::Error(error);
  fd_ = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) return Status::Error("UdpPacketSender: socket(): " + std::string(std::strerror(errno)));
  const int one = 1;
  setsockopt(fd_, SOL_SOCKET, SO_BROADCAST, &one, sizeof(one));
  config_ = config;
  sent_ = 0;
  return Status::Ok();
}

Status UdpPacketSender::Open(const std::string& host, uint16_t port) {
  UdpSenderConfig config;
  config.host = host;
  config.data_port = config.position_port = port;
  return Open(config);
}

Status UdpPacketSender::Send(const LidarPacket& packet) {
  if (fd_ < 0) return Status::Error("UdpPacketSender: Send before Open");
  const uint16_t port = packet.udp_port == kPositionPort ? config_.position_port : config_.data_port;
  sockaddr_in addr;
  MakeAddress(config_.host, port, &addr);
  const ssize_t n = sendto(fd_, packet.payload.data(), packet.payload.size(), 0,
                           reinterpret_cast<sockaddr*>(&addr), sizeof(addr));
  if (n != static_cast<ssize_t>(packet.payload.size())) {
    return Status::Error("UdpPacketSender: send to " + config_.host + ":" + std::to_string(port) + ": " +
                         (n < 0 ? std::strerror(errno) : "short write"));
  }
  ++sent_;
  return Status::Ok();
}

Status UdpPacketSender::SendAll(const std::vector<LidarPacket>& packets, double rate) {
  PacketPacer pacer(rate);
  for (std::size_t i = 0; i < packets.size(); ++i) {
    pacer.WaitUntilDue(packets[i].t_capture_s);
    const Status s = Send(packets[i]);
    if (!s) return Status::Error(s.message + " (packet " + std::to_string(i) + ")");
  }
  return Status::Ok();
}

void UdpPacketSender::Close() {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
}

}  // namespace rotolidar
