// Fault injection between the sim's streams and the recording (contract in faults.hpp).
#include "sim/faults/faults.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/wire/vlp16.hpp"

namespace rotolidar::sim {
namespace {

bool CheckFault(bool ok, const std::string& field, const char* what, std::string* error) {
  if (!ok && error) *error = "faults." + field + ": " + what;
  return ok;
}

bool Probability(double p, bool one_allowed, const std::string& field, std::string* error) {
  const bool ok = std::isfinite(p) && p >= 0.0 && (one_allowed ? p <= 1.0 : p < 1.0);
  return CheckFault(ok, field, one_allowed ? "must be in [0, 1]" : "must be in [0, 1)", error);
}

bool NonNegative(double x, const std::string& field, std::string* error) {
  return CheckFault(std::isfinite(x) && x >= 0.0, field, "must be finite and >= 0", error);
}

bool ValidInterval(double start_s, double duration_s, const std::string& name, std::string* error) {
  return NonNegative(start_s, name + ".start_s", error) && NonNegative(duration_s, name + ".duration_s", error);
}

bool IsData(const LidarPacket& p) {
  return p.udp_port != kVlp16PositionPort && p.payload.size() == kVlp16PacketBytes;
}

/// Clips each component to [-range, range] (range > 0); true when any was clipped.
bool Clip(double range, Eigen::Vector3d* v) {
  if (!(range > 0.0)) return false;
  const Eigen::Vector3d clipped = v->cwiseMax(-range).cwiseMin(range);
  const bool changed = clipped != *v;
  *v = clipped;
  return changed;
}

/// Records t_s into a [first, last] interval whose `count` hits came before.
void Extend(size_t count, double t_s, std::array<double, 2>* interval) {
  if (count == 0) (*interval)[0] = t_s;
  (*interval)[1] = t_s;
}

}  // namespace

bool FaultConfig::LidarEnabled() const {
  return lidar_loss.probability > 0.0 || lidar_loss.burst_rate_hz > 0.0 || lidar_duplicate.probability > 0.0 ||
         lidar_reorder.probability > 0.0 || lidar_blind.Enabled();
}

bool FaultConfig::Enabled() const {
  return LidarEnabled() || encoder_freeze.Enabled() || imu_dropout.Interval().Enabled() ||
         imu_dropout.probability > 0.0 || imu_saturation.gyro_range_radps > 0.0 ||
         imu_saturation.accel_range_mps2 > 0.0;
}

bool FaultConfig::Validate(std::string* error) const {
  const LidarLossFault& l = lidar_loss;
  return Probability(l.probability, false, "lidar_loss.probability", error) &&
         NonNegative(l.burst_rate_hz, "lidar_loss.burst_rate_hz", error) &&
         CheckFault(l.burst_length_packets >= 1 && l.burst_length_packets <= 1000000, "lidar_loss.burst_length_packets",
               "must be in [1, 1000000]", error) &&
         Probability(lidar_duplicate.probability, true, "lidar_duplicate.probability", error) &&
         Probability(lidar_reorder.probability, true, "lidar_reorder.probability", error) &&
         CheckFault(lidar_reorder.max_distance_packets >= 1 && lidar_reorder.max_distance_packets <= 1000,
               "lidar_reorder.max_distance_packets", "must be in [1, 1000]", error) &&
         ValidInterval(lidar_blind.start_s, lidar_blind.duration_s, "lidar_blind", error) &&
         ValidInterval(encoder_freeze.start_s, encoder_freeze.duration_s, "encoder_freeze", error) &&
         ValidInterval(imu_dropout.start_s, imu_dropout.duration_s, "imu_dropout", error) &&
         Probability(imu_dropout.probability, false, "imu_dropout.probability", error) &&
         NonNegative(imu_saturation.gyro_range_radps, "imu_saturation.gyro_range_radps", error) &&
         NonNegative(imu_saturation.accel_range_mps2, "imu_saturation.accel_range_mps2", error);
}

void BlindVlp16Payload(std::vector<uint8_t>* payload) {
  if (payload->size() != kVlp16PacketBytes) return;
  for (int block = 0; block < 12; ++block)
    for (int channel = 0; channel < 32; ++channel) {
      uint8_t* record = payload->data() + 100 * block + 4 + 3 * channel;  // distance uint16, reflectivity uint8
      record[0] = record[1] = record[2] = 0;
    }
}

FaultyWriter::FaultyWriter(const FaultConfig& config, uint64_t run_seed, RecordingWriter* out)
    : config_(config),
      out_(out),
      loss_rng_(run_seed, "fault.lidar_loss"),
      burst_rng_(run_seed, "fault.lidar_burst"),
      duplicate_rng_(run_seed, "fault.lidar_duplicate"),
      reorder_rng_(run_seed, "fault.lidar_reorder"),
      imu_dropout_rng_(run_seed, "fault.imu_dropout") {
  truth_.config = config;
  lidar_on_ = config.LidarEnabled();
  any_on_ = config.Enabled();
}

bool FaultyWriter::InBurst(double t_s) {
  const double rate = config_.lidar_loss.burst_rate_hz;
  if (!(rate > 0.0)) return false;
  const auto gap = [&] { return -std::log(1.0 - burst_rng_.Uniform()) / rate; };  // exponential inter-arrival
  if (next_burst_s_ < 0.0) next_burst_s_ = t_s + gap();
  while (t_s >= next_burst_s_) {
    if (burst_left_ == 0) truth_.lidar.bursts.push_back({t_s, t_s, 0.0});
    burst_left_ = config_.lidar_loss.burst_length_packets;
    next_burst_s_ += gap();
  }
  if (burst_left_ == 0) return false;
  --burst_left_;
  return true;
}

bool FaultyWriter::Lost(double t_s, double u_loss) {
  if (InBurst(t_s)) {
    ++truth_.lidar.lost_burst;
    std::array<double, 3>& burst = truth_.lidar.bursts.back();
    burst[1] = t_s;
    burst[2] += 1.0;
    return true;
  }
  if (u_loss < config_.lidar_loss.probability) return ++truth_.lidar.lost_random, true;
  return false;
}

Status FaultyWriter::Write(const LidarPacket& packet) {
  if (!lidar_on_) return out_->Write(packet);
  if (!IsData(packet)) return Reorder({packet, false, false, 0}, false, 0);
  const size_t index = truth_.lidar.data_packets_in++;
  // One draw per stream and input data packet, always: a fault's decisions never depend on another fault's.
  const double u_loss = config_.lidar_loss.probability > 0.0 ? loss_rng_.Uniform() : 1.0;
  const double u_duplicate = config_.lidar_duplicate.probability > 0.0 ? duplicate_rng_.Uniform() : 1.0;
  const bool reorder = config_.lidar_reorder.probability > 0.0;
  const double u_reorder = reorder ? reorder_rng_.Uniform() : 1.0;
  const double u_distance = reorder ? reorder_rng_.Uniform() : 0.0;
  const double t = packet.t_capture_s;
  if (Lost(t, u_loss)) return Status::Ok();
  Held held{packet, true, false, index};
  if (config_.lidar_blind.Contains(t)) {
    BlindVlp16Payload(&held.packet.payload);
    Extend(truth_.lidar.blinded++, t, &truth_.lidar.blinded_interval_s);
  }
  const int n = config_.lidar_reorder.max_distance_packets;
  const int distance = std::min(n, 1 + static_cast<int>(u_distance * n));
  const bool swap = u_reorder < config_.lidar_reorder.probability;
  const bool duplicate = u_duplicate < config_.lidar_duplicate.probability;
  Held copy = held;
  copy.copy = true;
  if (Status s = Reorder(std::move(held), swap, distance); !s) return s;
  if (!duplicate) return Status::Ok();
  ++truth_.lidar.duplicated;
  return Reorder(std::move(copy), false, 0);
}

Status FaultyWriter::Reorder(Held held, bool start_swap, int distance) {
  if (held_.empty()) {
    if (!start_swap) return Emit(held);
    held_.push_back(std::move(held));
    swap_countdown_ = distance;
    return Status::Ok();
  }
  // A swap is pending: everything queues behind its first packet; the partner is the distance-th original.
  const bool partner = held.data && !held.copy && --swap_countdown_ == 0;
  held_.push_back(std::move(held));
  if (!partner) return Status::Ok();
  std::swap(held_.front().packet.payload, held_.back().packet.payload);  // capture times stay in their slots
  std::swap(held_.front().index, held_.back().index);
  std::swap(held_.front().copy, held_.back().copy);
  ++truth_.lidar.swaps;
  return FlushHeld();
}

Status FaultyWriter::Emit(const Held& held) {
  if (held.data) {
    LidarFaultTruth& t = truth_.lidar;
    ++t.data_packets_out;
    if (seen_.size() <= held.index) seen_.resize(held.index + 1, 0);
    if (!seen_[held.index]) {
      if (any_written_ && held.index < newest_written_) ++t.arrived_after_newer;
      seen_[held.index] = 1;
      newest_written_ = any_written_ ? std::max(newest_written_, held.index) : held.index;
      any_written_ = true;
    }
  }
  return out_->Write(held.packet);
}

Status FaultyWriter::FlushHeld() {
  std::vector<Held> held = std::move(held_);
  held_.clear();
  swap_countdown_ = 0;
  for (const Held& h : held)
    if (Status s = Emit(h); !s) return s;
  return Status::Ok();
}

Status FaultyWriter::Write(const ImuSample& sample) {
  if (!any_on_) return out_->Write(sample);
  ImuFaultTruth& t = truth_.imu;
  ++t.samples_in;
  const double u = config_.imu_dropout.probability > 0.0 ? imu_dropout_rng_.Uniform() : 1.0;
  if (config_.imu_dropout.Interval().Contains(sample.t_s)) {
    Extend(t.dropped_interval++, sample.t_s, &t.dropped_interval_s);
    return Status::Ok();
  }
  if (u < config_.imu_dropout.probability) return ++t.dropped_random, Status::Ok();
  ImuSample s = sample;
  const bool gyro = Clip(config_.imu_saturation.gyro_range_radps, &s.gyro_radps);
  const bool accel = Clip(config_.imu_saturation.accel_range_mps2, &s.accel_mps2);
  t.saturated_samples += (gyro || accel) ? 1 : 0;
  return out_->Write(s);
}

Status FaultyWriter::Write(const EncoderSample& sample) {
  if (!config_.encoder_freeze.Enabled()) return out_->Write(sample);
  if (!config_.encoder_freeze.Contains(sample.t_s)) {
    have_encoder_count_ = true;
    last_encoder_count_ = sample.count;
    return out_->Write(sample);
  }
  if (!have_encoder_count_) have_encoder_count_ = true, last_encoder_count_ = sample.count;  // frozen from its start
  EncoderFaultTruth& t = truth_.encoder;
  Extend(t.frozen_samples++, sample.t_s, &t.frozen_interval_s);
  t.frozen_count = last_encoder_count_;
  EncoderSample frozen = sample;
  frozen.count = last_encoder_count_;
  return out_->Write(frozen);
}

Status FaultyWriter::Close() {
  if (Status s = FlushHeld(); !s) return s;
  return out_->Close();
}

}  // namespace rotolidar::sim
