// VLP-16 decoder: data packets -> timed points in the lidar frame (contract in vlp16.hpp).
#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/wire/vlp16.hpp"
#include "core/util/log.hpp"

namespace rotolidar {
namespace {

constexpr double kDegToRad = M_PI / 180.0;
constexpr double kCentidegToRad = 0.01 * kDegToRad;
constexpr double kMaxPlausibleStepCentideg = 1000.0;  // 10 deg per block (pair): 1200 rpm moves ~0.8 deg
constexpr int64_t kHourUs = static_cast<int64_t>(kVlp16MicrosPerHour);
constexpr double kHourS = 3600.0;
constexpr uint8_t kPpsLocked = 2;

uint8_t ReturnTypeOf(Vlp16ReturnMode mode, int block) {
  if (mode == Vlp16ReturnMode::kDual) return block % 2 == 0 ? kReturnLast : kReturnStrongest;  // even = last
  return mode == Vlp16ReturnMode::kLast ? kReturnLast : kReturnStrongest;
}

}  // namespace

bool Vlp16ReturnSelected(Vlp16ReturnFilter filter, uint8_t return_type) {
  if (filter == Vlp16ReturnFilter::kAll || return_type == kReturnStrongestAndLast) return true;
  return (filter == Vlp16ReturnFilter::kStrongest) == (return_type == kReturnStrongest);
}

bool Vlp16DecoderConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = "Vlp16DecoderConfig: " + m;
    return false;
  };
  if (!(min_range_m >= 0.0)) return fail("min_range_m must be >= 0");
  if (!(max_range_m > min_range_m)) return fail("max_range_m must be > min_range_m");
  if (return_filter != Vlp16ReturnFilter::kAll && return_filter != Vlp16ReturnFilter::kStrongest &&
      return_filter != Vlp16ReturnFilter::kLast) {
    return fail("return_filter must be all, strongest or last");
  }
  if (!std::isfinite(lidar_clock_offset_s)) return fail("lidar_clock_offset_s must be finite");
  return true;
}

Vlp16Decoder::Vlp16Decoder(const LidarIntrinsics& intrinsics, const Vlp16DecoderConfig& config)
    : intrinsics_(intrinsics), config_(config) {
  std::string error;
  ROTOLIDAR_CHECK(config_.Validate(&error), error);
  std::array<int, 16> order;
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return intrinsics_.elevation_deg[a] < intrinsics_.elevation_deg[b];
  });
  for (int ring = 0; ring < 16; ++ring) ring_of_laser_[order[ring]] = static_cast<uint8_t>(ring);
  for (int id = 0; id < 16; ++id) {
    // Vlp16RayDirection's elevation terms, computed once.
    const Eigen::Vector3d d = Vlp16RayDirection(intrinsics_.elevation_deg[id] * kDegToRad, 0.0);
    cos_elevation_[id] = d.x();
    sin_elevation_[id] = d.z();
  }
}

Seconds Vlp16Decoder::UnwrapToRigTime(uint32_t timestamp_us) {
  int64_t unwrapped = hour_ * kHourUs + timestamp_us;
  if (have_time_) {
    const int64_t diff = unwrapped - last_unwrapped_us_;
    if (diff < -kHourUs / 2) ++hour_;
    if (diff > kHourUs / 2) --hour_;
    unwrapped = hour_ * kHourUs + timestamp_us;
  }
  have_time_ = true;
  last_unwrapped_us_ = unwrapped;
  return static_cast<double>(unwrapped) * 1e-6 + config_.lidar_clock_offset_s;
}

std::array<double, 12> Vlp16Decoder::AzimuthSteps() const {
  const int stride = raw_.return_mode == static_cast<uint8_t>(Vlp16ReturnMode::kDual) ? 2 : 1;
  std::array<double, 12> steps{};
  double last_good = -1.0;
  for (int b = 0; b < 12; b += stride) {
    double d = last_good;  // the last block (pair) reuses the previous difference
    if (b + stride < 12) {
      const int a0 = raw_.blocks[b].azimuth_centideg, a1 = raw_.blocks[b + stride].azimuth_centideg;
      const double step = static_cast<double>((a1 - a0 + 36000) % 36000);
      if (step <= kMaxPlausibleStepCentideg) d = last_good = step;
    }
    for (int k = 0; k < stride; ++k) steps[b + k] = d;
  }
  // Leading implausible steps (before any good one) take the first good one; none at all: no interpolation.
  for (int b = 11; b >= 0; --b) {
    if (steps[b] < 0.0) steps[b] = (b + 1 < 12 && steps[b + 1] >= 0.0) ? steps[b + 1] : 0.0;
  }
  return steps;
}

// Azimuth of laser l in a firing = base + d_az * l * 2.304 / 110.592 [0.01 deg] (driver formula). Its cosine and
// sine come from the base angle's (one sincos per firing) rotated by the per-laser increment (cached per d_az):
// the same numbers as direct evaluation to ~1e-16.
void Vlp16Decoder::DecodeFiring(int block, int firing, double d_az, double packet_t_s,
                                std::vector<LidarPoint>* appended) {
  const auto mode = static_cast<Vlp16ReturnMode>(raw_.return_mode);
  const bool dual = mode == Vlp16ReturnMode::kDual;
  const int stride = dual ? 2 : 1;
  if (d_az != cached_d_az_) {
    for (int l = 0; l < 16; ++l) {
      const double inc = d_az * l * 2.304 / 110.592 * kCentidegToRad;
      cos_increment_[l] = std::cos(inc);
      sin_increment_[l] = std::sin(inc);
    }
    cached_d_az_ = d_az;
  }
  const double base_centideg = raw_.blocks[block].azimuth_centideg + d_az * firing * (55.296 / 110.592);
  const double cos_base = std::cos(base_centideg * kCentidegToRad);
  const double sin_base = std::sin(base_centideg * kCentidegToRad);
  const int seq = (dual ? block : 2 * block) + firing;
  const double firing_t_s = packet_t_s + seq * kVlp16SequencePeriodS;
  for (int laser = 0; laser < 16; ++laser) {
    const int ch = 16 * firing + laser;
    // Dual: one echo repeated in both blocks (the strongest was also the last) is one point unless asked for both.
    const bool duplicate = dual && !config_.keep_duplicate_dual_returns &&
                           raw_.blocks[block].distance_2mm[ch] == raw_.blocks[block + 1].distance_2mm[ch] &&
                           raw_.blocks[block].reflectivity[ch] == raw_.blocks[block + 1].reflectivity[ch];
    for (int k = 0; k < (duplicate ? 1 : stride); ++k) {  // dual: the even (last) block, then the odd (strongest)
      const Vlp16RawBlock& raw_block = raw_.blocks[block + k];
      const uint16_t d = raw_block.distance_2mm[ch];
      if (d == 0) continue;
      const double range_m = d * kVlp16DistanceUnitM;
      if (range_m < config_.min_range_m || range_m > config_.max_range_m) continue;
      const uint8_t return_type = duplicate ? kReturnStrongestAndLast : ReturnTypeOf(mode, block + k);
      if (!Vlp16ReturnSelected(config_.return_filter, return_type)) continue;
      merged_dual_duplicates_ += duplicate ? 1 : 0;
      const double cos_az = cos_base * cos_increment_[laser] - sin_base * sin_increment_[laser];
      const double sin_az = sin_base * cos_increment_[laser] + cos_base * sin_increment_[laser];
      const double horizontal_m = cos_elevation_[laser] * range_m;
      double az = base_centideg + d_az * laser * (2.304 / 110.592);
      if (az >= 36000.0) az -= 36000.0;
      LidarPoint point;
      point.x_m = static_cast<float>(horizontal_m * cos_az);
      point.y_m = static_cast<float>(-horizontal_m * sin_az);
      point.z_m = static_cast<float>(intrinsics_.vertical_offset_m[laser] + sin_elevation_[laser] * range_m);
      point.intensity = raw_block.reflectivity[ch];
      point.azimuth_deg = static_cast<float>(az * 0.01);
      if (point.azimuth_deg >= 360.f) point.azimuth_deg = 0.f;  // float rounding of 359.99999
      point.ring = ring_of_laser_[laser];
      point.laser_id = static_cast<uint8_t>(laser);
      point.return_type = return_type;
      point.t_s = firing_t_s + laser * kVlp16FiringPeriodS;
      appended->push_back(point);
    }
  }
}

void Vlp16Decoder::TakePosition(const Vlp16PositionPacket& position) {
  last_position_ = position;
  double utc_s = 0.0;
  if (position.pps_status != kPpsLocked || !ParseGprmcUtc(position.nmea, &utc_s)) return;
  hour_start_unix_s_ = std::round((utc_s - position.timestamp_us * 1e-6) / kHourS) * kHourS;
}

Status Vlp16Decoder::Decode(const LidarPacket& packet, std::vector<LidarPoint>* appended) {
  ROTOLIDAR_CHECK(appended != nullptr, "null output");
  if (packet.udp_port == kVlp16PositionPort || packet.payload.size() == kVlp16PositionPacketBytes) {
    Vlp16PositionPacket position;
    const Status s = ParseVlp16PositionPacket(packet.payload.data(), packet.payload.size(), &position);
    if (s) TakePosition(position);
    return s;
  }
  const Status s = ParseVlp16DataPacket(packet.payload.data(), packet.payload.size(), &raw_);
  if (!s) return s;
  const double packet_t_s = UnwrapToRigTime(raw_.timestamp_us);
  const std::array<double, 12> steps = AzimuthSteps();
  if (appended->capacity() - appended->size() < 384) {  // grow geometrically: never one packet at a time
    appended->reserve(std::max<std::size_t>(2 * appended->capacity(), appended->size() + 384));
  }
  // Emit in firing order so that times never decrease; in dual mode a pair's two returns of one firing are
  // adjacent (last, then strongest) and share their time.
  const int stride = raw_.return_mode == static_cast<uint8_t>(Vlp16ReturnMode::kDual) ? 2 : 1;
  for (int b = 0; b < 12; b += stride) {
    for (int firing = 0; firing < 2; ++firing) DecodeFiring(b, firing, steps[b], packet_t_s, appended);
  }
  return Status::Ok();
}

}  // namespace rotolidar
