// Rig samples over UDP (contract in rig_udp.hpp).
#include "core/wire/rig_udp.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

namespace rotolidar {

bool RigSourceConfig::Validate(std::string* error) const {
  if (queue_capacity == 0) {
    if (error) *error = "RigSourceConfig: queue_capacity must be >= 1";
    return false;
  }
  return socket.Validate(error);
}

RigSampleSource::~RigSampleSource() { Stop(); }

Status RigSampleSource::Start(const RigSourceConfig& config) {
  std::string error;
  if (!config.Validate(&error)) return Status::Error(error);
  if (socket_.is_open() || running_) return Status::Error("RigSampleSource: already started");
  if (Status s = socket_.Open(config.socket); !s) return Status::Error("RigSampleSource: " + s.message);
  port_ = socket_.port();
  config_ = config;
  running_ = true;
  thread_ = std::thread(&RigSampleSource::ReceiveLoop, this);
  return Status::Ok();
}

void RigSampleSource::CountSequence(uint32_t sequence) {
  if (have_sequence_) {
    const int32_t step = static_cast<int32_t>(sequence - next_sequence_);  // wrap-safe
    if (step < 0) {
      ++out_of_order_;
      return;  // late or repeated: the reference stays
    }
    lost_ += static_cast<std::size_t>(step);
  }
  have_sequence_ = true;
  next_sequence_ = sequence + 1;
}

void RigSampleSource::ReceiveLoop() {
  std::vector<uint8_t> buffer(65536);
  RigDatagram datagram;
  while (running_) {
    const long n = socket_.Receive(buffer.data(), buffer.size(), 0.02);  // 20 ms: how long Stop may wait
    kernel_dropped_ = socket_.kernel_dropped();
    if (n < 0) continue;
    const Status s = DecodeRigDatagram(buffer.data(), std::min<std::size_t>(n, buffer.size()), &datagram);
    if (!s) {
      // The message first, then the count, both under the lock: whoever sees malformed() > 0 finds its message.
      std::lock_guard<std::mutex> lock(mutex_);
      last_error_ = s.message;
      ++malformed_;
      continue;
    }
    ++datagrams_;
    CountSequence(datagram.sequence);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const RigSample& sample : datagram.samples) {
        if (queue_.size() >= config_.queue_capacity) {
          ++dropped_;
          continue;
        }
        queue_.push_back(sample);
        ++samples_;
      }
    }
    cv_.notify_one();
  }
}

std::size_t RigSampleSource::PopAll(std::vector<RigSample>* out, double timeout_s) {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait_for(lock, std::chrono::duration<double>(std::max(0.0, timeout_s)),
               [&] { return !queue_.empty() || !running_; });
  const std::size_t n = queue_.size();
  out->insert(out->end(), queue_.begin(), queue_.end());
  queue_.clear();
  return n;
}

std::string RigSampleSource::last_error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_error_;
}

void RigSampleSource::Stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  socket_.Close();
  cv_.notify_all();
}

RigSampleSender::~RigSampleSender() { Close(); }

Status RigSampleSender::Open(const std::string& host, uint16_t port) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1)
    return Status::Error("RigSampleSender: host '" + host + "' is not a dotted IPv4 address");
  fd_ = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd_ < 0) return Status::Error("RigSampleSender: socket(): " + std::string(std::strerror(errno)));
  address_.assign(reinterpret_cast<const uint8_t*>(&addr), reinterpret_cast<const uint8_t*>(&addr) + sizeof(addr));
  return Status::Ok();
}

Status RigSampleSender::Add(const RigSample& sample, std::size_t batch) {
  pending_.samples.push_back(sample);
  if (pending_.samples.size() >= std::min<std::size_t>(std::max<std::size_t>(batch, 1), kRigMaxRecords))
    return Flush();
  return Status::Ok();
}

Status RigSampleSender::Flush() {
  if (pending_.samples.empty()) return Status::Ok();
  if (fd_ < 0) return Status::Error("RigSampleSender: not open");
  pending_.sequence = sequence_;
  if (Status s = EncodeRigDatagram(pending_, &bytes_); !s) return s;
  pending_.samples.clear();
  const ssize_t n = sendto(fd_, bytes_.data(), bytes_.size(), 0, reinterpret_cast<const sockaddr*>(address_.data()),
                           static_cast<socklen_t>(address_.size()));
  if (n != static_cast<ssize_t>(bytes_.size()))
    return Status::Error("RigSampleSender: sendto: " + std::string(std::strerror(errno)));
  ++sequence_;
  return Status::Ok();
}

void RigSampleSender::Close() {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
}

}  // namespace rotolidar
