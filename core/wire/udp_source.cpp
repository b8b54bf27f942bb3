// UDP receive of VLP-16 packets (contract in udp_source.hpp).
#include "core/wire/udp_source.hpp"

#include <chrono>
#include <cmath>

#include "core/wire/vlp16.hpp"

namespace rotolidar {
namespace {

double SteadyNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

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
  if (socket_.is_open() || running_) return Status::Error("UdpPacketSource: already started");
  UdpSocketConfig socket_config;
  socket_config.bind_address = config.bind_address;
  socket_config.port = config.port;
  socket_config.rcvbuf_bytes = config.rcvbuf_bytes;
  if (Status s = socket_.Open(socket_config); !s) return Status::Error("UdpPacketSource: " + s.message);
  bound_port_ = socket_.port();
  rcvbuf_granted_ = socket_.rcvbuf_bytes();
  config_ = config;
  start_steady_s_ = SteadyNowS();
  running_ = true;
  thread_ = std::thread(&UdpPacketSource::ReceiveLoop, this);
  return Status::Ok();
}

void UdpPacketSource::ReceiveLoop() {
  std::vector<uint8_t> buffer(65536);
  while (running_) {
    const long n = socket_.Receive(buffer.data(), buffer.size(), 0.02);  // 20 ms: how long Stop may wait
    kernel_dropped_ = socket_.kernel_dropped();
    if (n < 0) continue;
    LidarPacket packet;
    packet.t_capture_s = config_.rig_time_at_start_s + (SteadyNowS() - start_steady_s_);
    if (static_cast<std::size_t>(n) == kVlp16PacketBytes) {
      packet.udp_port = kVlp16DataPort;
      uint32_t stamp = 0;
      uint8_t mode = 0;
      Vlp16DataTimestamp(buffer.data(), static_cast<std::size_t>(n), &stamp, &mode);
      gaps_.Add(stamp, mode);
      lost_ = gaps_.lost();
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
  socket_.Close();
  cv_.notify_all();
}

}  // namespace rotolidar
