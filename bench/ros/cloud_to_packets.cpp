// sensor_msgs/PointCloud2 -> VLP-16 data packets (contract in cloud_to_packets.hpp).
#include "bench/ros/cloud_to_packets.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

namespace rotolidar::bench::rosmsg {
namespace cloud_internal {  // named: the unity build puts several .cpp files into one

constexpr double kSequenceS = kVlp16SequencePeriodS;   // 55.296 us between firing sequences
constexpr int kSlots = kVlp16SequencesPerPacket;       // 24 sequences per single-return packet
constexpr double kSameFiringTolS = 1e-6;               // points of one sequence: times within 1 us
constexpr double kGridTolS = 0.5e-6;                   // a firing continues the grid within 0.5 us
constexpr double kMaxElevationErrorDeg = 2.0;          // the VLP-16's ring spacing
constexpr double kRadToCentideg = 18000.0 / M_PI;
constexpr double kMaxRelativeTimeS = 3600.0;           // a point's time field beyond this is not relative

const char* TypeName(uint8_t t) {
  static const char* names[] = {"?", "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"};
  return t >= 1 && t <= 8 ? names[t] : "unknown";
}

std::size_t TypeSize(uint8_t t) {
  static const std::size_t sizes[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
  return t <= 8 ? sizes[t] : 0;
}

/// A little-endian field value of PointField type `t` as a double.
double ReadNumber(const uint8_t* p, uint8_t t) {
  uint64_t u = 0;
  for (std::size_t i = 0; i < TypeSize(t); ++i) u |= static_cast<uint64_t>(p[i]) << (8 * i);
  switch (static_cast<PointFieldType>(t)) {
    case PointFieldType::kInt8: return static_cast<int8_t>(u);
    case PointFieldType::kUint8: return static_cast<uint8_t>(u);
    case PointFieldType::kInt16: return static_cast<int16_t>(u);
    case PointFieldType::kUint16: return static_cast<uint16_t>(u);
    case PointFieldType::kInt32: return static_cast<int32_t>(u);
    case PointFieldType::kUint32: return static_cast<uint32_t>(u);
    case PointFieldType::kFloat32: {
      const uint32_t bits = static_cast<uint32_t>(u);
      float f;
      std::memcpy(&f, &bits, 4);
      return f;
    }
    case PointFieldType::kFloat64: {
      double d;
      std::memcpy(&d, &u, 8);
      return d;
    }
  }
  return 0.0;
}

std::string FieldList(const PointCloud2Msg& c) {
  std::string s;
  for (const PointFieldMsg& f : c.fields) s += (s.empty() ? "" : ", ") + f.name + " (" + TypeName(f.datatype) + ")";
  return s.empty() ? "none" : s;
}

/// Finds field `name` and checks it: one of `types`, count 1, inside point_step. *out = nullptr when absent.
Status Field(const PointCloud2Msg& c, const std::string& name, std::vector<PointFieldType> types,
             const std::string& expected, const PointFieldMsg** out) {
  *out = nullptr;
  for (const PointFieldMsg& f : c.fields)
    if (f.name == name) *out = &f;
  if (*out == nullptr) return Status::Ok();
  const PointFieldMsg& f = **out;
  const std::string where = "field '" + name + "': ";
  if (std::find(types.begin(), types.end(), static_cast<PointFieldType>(f.datatype)) == types.end())
    return Status::Error(where + "datatype " + std::to_string(f.datatype) + " (" + TypeName(f.datatype) +
                         "), expected " + expected);
  if (f.count != 1) return Status::Error(where + "count " + std::to_string(f.count) + ", expected 1");
  if (static_cast<uint64_t>(f.offset) + TypeSize(f.datatype) > c.point_step)
    return Status::Error(where + "offset " + std::to_string(f.offset) + " + " +
                         std::to_string(TypeSize(f.datatype)) + " bytes does not fit in point_step " +
                         std::to_string(c.point_step));
  return Status::Ok();
}

Status CheckLayout(const PointCloud2Msg& c) {
  if (c.is_bigendian) return Status::Error("field 'is_bigendian': big-endian point data is not supported");
  if (c.point_step == 0 && c.width * static_cast<uint64_t>(c.height) > 0)
    return Status::Error("field 'point_step': 0 bytes per point");
  const uint64_t row = static_cast<uint64_t>(c.width) * c.point_step;
  if (c.row_step < row)
    return Status::Error("field 'row_step': " + std::to_string(c.row_step) + " < width " + std::to_string(c.width) +
                         " x point_step " + std::to_string(c.point_step));
  const uint64_t need = static_cast<uint64_t>(c.row_step) * c.height;
  if (c.data.size() < need)
    return Status::Error("field 'data': " + std::to_string(c.data.size()) + " bytes, row_step x height = " +
                         std::to_string(need));
  return Status::Ok();
}

/// The fields ReadCloudPoints uses (time: `time` in s, else `t` in ns).
struct Layout {
  const PointFieldMsg *xyz[3] = {}, *ring = nullptr, *time = nullptr, *intensity = nullptr;
  double time_scale = 1.0;
};

Status FindFields(const PointCloud2Msg& c, Layout* l) {
  using T = PointFieldType;
  const char* names[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    if (Status s = Field(c, names[i], {T::kFloat32, T::kFloat64}, "float32 or float64", &l->xyz[i]); !s) return s;
    if (!l->xyz[i])
      return Status::Error(std::string("field '") + names[i] + "': missing (needs x, y, z, ring, time or t; the " +
                           "cloud has " + FieldList(c) + ")");
  }
  if (Status s = Field(c, "ring", {T::kUint16, T::kUint8}, "uint16 (or uint8): the laser's ring, 0 = lowest", &l->ring);
      !s)
    return s;
  if (!l->ring)
    return Status::Error("field 'ring': missing (uint16, the laser's ring, 0 = lowest elevation, as the velodyne "
                         "driver writes it; the cloud has " + FieldList(c) + ")");
  if (Status s = Field(c, "time", {T::kFloat32, T::kFloat64}, "float32 (seconds relative to header.stamp)", &l->time);
      !s)
    return s;
  if (!l->time) {
    if (Status s = Field(c, "t", {T::kUint32}, "uint32 (nanoseconds relative to header.stamp)", &l->time); !s) return s;
    l->time_scale = 1e-9;
  }
  if (!l->time)
    return Status::Error("field 'time': missing (each point's firing time: 'time' float32 [s] or 't' uint32 [ns], "
                         "relative to header.stamp; an absolute 'timestamp' is not supported; the cloud has " +
                         FieldList(c) + ")");
  const std::vector<T> any{T::kInt8, T::kUint8, T::kInt16, T::kUint16, T::kInt32, T::kUint32, T::kFloat32, T::kFloat64};
  return Field(c, "intensity", any, "a numeric type", &l->intensity);
}

/// 0 when the points are in the VLP-16 frame and on their rings; else how far off [deg] (*el_deg: the point's).
double ElevationError(const Eigen::Vector3d& v, double range, double laser_el_deg, double* el_deg) {
  *el_deg = std::asin(std::clamp(v.z() / range, -1.0, 1.0)) * 180.0 / M_PI;
  return std::abs(*el_deg - laser_el_deg);
}

/// Points of one sequence, before grouping: the slot time and what the laser measured.
struct Ray {
  Seconds t_seq = 0.0;
  int laser = 0;
  uint16_t distance_2mm = 0;
  uint8_t reflectivity = 0;
  double az_centideg = 0.0;
  uint32_t index = 0;
};

double WrapCentideg(double a) {
  a = std::fmod(a, 36000.0);
  return a < 0.0 ? a + 36000.0 : a;
}

}  // namespace cloud_internal

Status ReadCloudPoints(const PointCloud2Msg& c, std::vector<CloudPoint>* points) {
  using namespace cloud_internal;  // NOLINT
  points->clear();
  if (Status s = CheckLayout(c); !s) return s;
  Layout l;
  if (Status s = FindFields(c, &l); !s) return s;
  points->reserve(static_cast<std::size_t>(c.width) * c.height);
  for (uint32_t r = 0; r < c.height; ++r) {
    for (uint32_t col = 0; col < c.width; ++col) {
      const uint8_t* p = c.data.data() + static_cast<std::size_t>(r) * c.row_step +
                         static_cast<std::size_t>(col) * c.point_step;
      CloudPoint q;
      q.index = r * c.width + col;
      q.x_m = static_cast<float>(ReadNumber(p + l.xyz[0]->offset, l.xyz[0]->datatype));
      q.y_m = static_cast<float>(ReadNumber(p + l.xyz[1]->offset, l.xyz[1]->datatype));
      q.z_m = static_cast<float>(ReadNumber(p + l.xyz[2]->offset, l.xyz[2]->datatype));
      if (!std::isfinite(q.x_m) || !std::isfinite(q.y_m) || !std::isfinite(q.z_m)) continue;
      if (q.x_m == 0.f && q.y_m == 0.f && q.z_m == 0.f) continue;
      q.ring = static_cast<uint16_t>(ReadNumber(p + l.ring->offset, l.ring->datatype));
      q.dt_s = ReadNumber(p + l.time->offset, l.time->datatype) * l.time_scale;
      if (!(std::abs(q.dt_s) <= kMaxRelativeTimeS))
        return Status::Error("point " + std::to_string(q.index) + ": field '" + l.time->name + "': " +
                             std::to_string(q.dt_s) + " s from header.stamp (not finite, or over an hour: the " +
                             "time must be relative to header.stamp; absolute times are not supported)");
      if (l.intensity) q.intensity = static_cast<float>(ReadNumber(p + l.intensity->offset, l.intensity->datatype));
      points->push_back(q);
    }
  }
  return Status::Ok();
}

std::array<int, 16> LaserOfRing(const LidarIntrinsics& lidar) {
  std::array<int, 16> order;
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return lidar.elevation_deg[a] < lidar.elevation_deg[b]; });
  return order;  // as Vlp16Decoder sorts them: ring_of_laser[order[ring]] = ring
}

int64_t EarliestSequenceOffsetNs(const std::vector<CloudPoint>& points, const LidarIntrinsics& lidar) {
  using namespace cloud_internal;  // NOLINT
  if (points.empty()) return 0;
  const std::array<int, 16> laser_of_ring = LaserOfRing(lidar);
  double min_s = std::numeric_limits<double>::infinity();
  for (const CloudPoint& p : points)
    min_s = std::min(min_s, p.dt_s - (p.ring < 16 ? laser_of_ring[p.ring] : 0) * kVlp16FiringPeriodS);
  return static_cast<int64_t>(std::floor(min_s * 1e9));
}

CloudPacketizer::CloudPacketizer(const LidarIntrinsics& lidar)
    : lidar_(lidar),
      laser_of_ring_(LaserOfRing(lidar)),
      encoder_(Vlp16ReturnMode::kStrongest, 0.0),
      rate_centideg_per_s_(lidar.rpm / 60.0 * 36000.0) {}

namespace cloud_internal {

/// The ray a point measured; fails on a ring >= 16, a range the wire format cannot hold or a point off its laser.
Status ToRay(const CloudPoint& p, Seconds stamp_rig_s, const LidarIntrinsics& lidar,
             const std::array<int, 16>& laser_of_ring, Ray* ray) {
  const std::string where = "point " + std::to_string(p.index) + " (ring " + std::to_string(p.ring) + "): ";
  if (p.ring >= 16) return Status::Error(where + "field 'ring': " + std::to_string(p.ring) + " >= 16 (VLP-16)");
  ray->laser = laser_of_ring[p.ring];
  const Eigen::Vector3d v = Eigen::Vector3d(p.x_m, p.y_m, p.z_m) - Vlp16RayOrigin(lidar.vertical_offset_m[ray->laser]);
  const double range = v.norm();
  const double d = std::round(range / kVlp16DistanceUnitM);
  if (d > 65535.0)
    return Status::Error(where + "range " + std::to_string(range) + " m exceeds the VLP-16 wire format's " +
                         "131.07 m (16-bit distance in 2 mm)");
  double el = 0.0;
  const double laser_el = lidar.elevation_deg[ray->laser];
  if (ElevationError(v, range, laser_el, &el) > kMaxElevationErrorDeg)
    return Status::Error(where + "elevation " + std::to_string(el) + " deg, laser " + std::to_string(ray->laser) +
                         " fires at " + std::to_string(laser_el) + " deg (calib lidar.elevation_deg): the cloud " +
                         "must be in the VLP-16's own frame (clouds transformed to another frame are not " +
                         "supported) with rings numbered from the lowest laser (0 = " +
                         std::to_string(lidar.elevation_deg[laser_of_ring[0]]) + " deg)");
  ray->distance_2mm = static_cast<uint16_t>(d);
  ray->reflectivity = static_cast<uint8_t>(std::isfinite(p.intensity) ? std::clamp(std::round(p.intensity), 0.f, 255.f)
                                                                      : 0.f);
  ray->az_centideg = WrapCentideg(std::atan2(-v.y(), v.x()) * kRadToCentideg);
  ray->t_seq = stamp_rig_s + p.dt_s - ray->laser * kVlp16FiringPeriodS;
  ray->index = p.index;
  return Status::Ok();
}

/// Rays sorted by time -> firings (rays within 1 us of a firing's first); fails on one laser twice in a firing.
Status GroupFirings(const std::vector<Ray>& rays, std::vector<CloudPacketizer::Firing>* firings) {
  std::size_t i = 0;
  while (i < rays.size()) {
    std::size_t j = i;
    double sum_t = 0.0;
    CloudPacketizer::Firing f;
    f.observed = true;
    int lowest = 16;
    for (; j < rays.size() && rays[j].t_seq - rays[i].t_seq <= kSameFiringTolS; ++j) {
      const Ray& r = rays[j];
      if (f.distance_2mm[r.laser] != 0)
        return Status::Error("point " + std::to_string(r.index) + ": a second point of laser " +
                             std::to_string(r.laser) + " in one firing sequence (dual-return clouds are not " +
                             "supported)");
      f.distance_2mm[r.laser] = r.distance_2mm;
      f.reflectivity[r.laser] = r.reflectivity;
      sum_t += r.t_seq;
      if (r.laser < lowest) lowest = r.laser, f.az_centideg = r.az_centideg;
    }
    f.t_s = sum_t / static_cast<double>(j - i);
    f.lever_s = lowest * kVlp16FiringPeriodS;
    firings->push_back(f);
    i = j;
  }
  return Status::Ok();
}

/// Median head speed [0.01 deg/s] between consecutive firings at most 4 sequences apart; nullopt with < 3 pairs.
std::optional<double> MeasureRate(const std::vector<CloudPacketizer::Firing>& firings) {
  std::vector<double> rates;
  for (std::size_t i = 1; i < firings.size(); ++i) {
    const auto &a = firings[i - 1], &b = firings[i];
    const double dt = (b.t_s + b.lever_s) - (a.t_s + a.lever_s);
    if (dt <= 0.0 || dt > 4 * kSequenceS) continue;
    double d = WrapCentideg(b.az_centideg - a.az_centideg);
    if (d > 18000.0) d -= 36000.0;
    rates.push_back(d / dt);
  }
  if (rates.size() < 3) return std::nullopt;
  std::nth_element(rates.begin(), rates.begin() + rates.size() / 2, rates.end());
  return rates[rates.size() / 2];
}

}  // namespace cloud_internal

Status CloudPacketizer::Add(Seconds stamp_rig_s, const std::vector<CloudPoint>& points,
                            std::vector<LidarPacket>* packets) {
  using namespace cloud_internal;  // NOLINT
  std::vector<Ray> rays(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    if (Status s = ToRay(points[i], stamp_rig_s, lidar_, laser_of_ring_, &rays[i]); !s) return s;
  std::stable_sort(rays.begin(), rays.end(), [](const Ray& a, const Ray& b) { return a.t_seq < b.t_seq; });
  std::vector<Firing> firings;
  if (Status s = GroupFirings(rays, &firings); !s) return s;
  if (const std::optional<double> rate = MeasureRate(firings)) {
    if (*rate <= 0.0)
      return Status::Error("the azimuth atan2(-y, x) does not increase with time (median " +
                           std::to_string(*rate / 100.0) + " deg/s): the VLP-16 turns clockwise seen from above " +
                           "in its own frame (x forward, y left, z up); a mirrored or transformed cloud is not " +
                           "supported");
    rate_centideg_per_s_ = *rate;
  }
  for (const Firing& f : firings)
    if (Status s = Place(f, packets); !s) return s;
  return Status::Ok();
}

Status CloudPacketizer::Place(const Firing& f, std::vector<LidarPacket>* packets) {
  using namespace cloud_internal;  // NOLINT
  long j = 0;
  if (run_) {
    const double k = (f.t_s - anchor_t_) / kSequenceS;
    j = std::lround(k);
    const long filled = static_cast<long>(slots_.size());
    const bool on_grid = std::abs(k - j) * kSequenceS <= kGridTolS && j >= filled && j < filled + kSlots;
    if (!on_grid) {
      if (f.t_s < packet_start_t_ - kGridTolS)
        return Status::Error("a firing at rig time " + std::to_string(f.t_s) + " s is earlier than the packet " +
                             "before it (" + std::to_string(packet_start_t_) + " s): clouds must come in time " +
                             "order and not overlap");
      Flush(packets);
    }
  }
  if (!run_) {
    run_ = true, anchor_observed_ = true, anchor_t_ = packet_start_t_ = f.t_s, j = 0;
  } else {
    if (j >= kSlots) {
      slots_.resize(kSlots);
      EmitPacket(packets);
      j -= kSlots;
    }
    slots_.resize(static_cast<std::size_t>(j));
    if (!anchor_observed_) anchor_t_ = packet_start_t_ = f.t_s - j * kSequenceS, anchor_observed_ = true;
  }
  slots_.push_back(f);
  if (static_cast<int>(slots_.size()) == kSlots) EmitPacket(packets);
  return Status::Ok();
}

void CloudPacketizer::Flush(std::vector<LidarPacket>* packets) {
  using namespace cloud_internal;  // NOLINT
  if (!slots_.empty()) {
    slots_.resize(kSlots);
    EmitPacket(packets);
  }
  run_ = false;
}

// A block's azimuth (0.01 deg, the value at its first firing's laser 0) comes from the point nearest that instant
// in time, moved back by the head speed: exact when laser 0 of the first firing has a point, off by (speed error x
// lever) otherwise. Blocks without points extrapolate from the nearest block that has some.
std::array<uint16_t, 12> CloudPacketizer::BlockAzimuths() const {
  using namespace cloud_internal;  // NOLINT
  std::array<double, 12> az{};
  std::array<double, 12> lever{};
  lever.fill(-1.0);
  for (int s = 0; s < kSlots; ++s) {
    const Firing& f = slots_[s];
    const int b = s / 2;
    const double l = (s % 2) * kSequenceS + f.lever_s;
    if (!f.observed || (lever[b] >= 0.0 && lever[b] <= l)) continue;
    lever[b] = l;
    az[b] = f.az_centideg - rate_centideg_per_s_ * l;
  }
  std::array<uint16_t, 12> out{};
  for (int b = 0; b < 12; ++b) {
    int nearest = -1;
    for (int c = 0; c < 12; ++c)
      if (lever[c] >= 0.0 && (nearest < 0 || std::abs(c - b) < std::abs(nearest - b))) nearest = c;
    if (nearest < 0) continue;  // no point in the packet: Place never emits such a packet
    const double a = az[nearest] + rate_centideg_per_s_ * (b - nearest) * 2 * kSequenceS;
    out[b] = static_cast<uint16_t>(static_cast<long>(std::lround(WrapCentideg(a))) % 36000);
  }
  return out;
}

// The encoder floors the first slot's time to a whole microsecond; half a microsecond added first rounds it to
// the nearest one instead. The capture time is the encoder's model, kept non-decreasing across packets.
void CloudPacketizer::EmitPacket(std::vector<LidarPacket>* packets) {
  using namespace cloud_internal;  // NOLINT
  const std::array<uint16_t, 12> azimuths = BlockAzimuths();
  std::optional<LidarPacket> packet;
  for (int s = 0; s < kSlots; ++s) {
    Vlp16FiringSequence seq;
    seq.t_s = anchor_t_ + 0.5e-6 + s * kSequenceS;
    seq.azimuth_centideg = azimuths[s / 2];
    seq.distance_2mm = slots_[s].distance_2mm;
    seq.reflectivity = slots_[s].reflectivity;
    packet = encoder_.Add(seq);
  }
  packet->t_capture_s = std::max(
      last_capture_t_, anchor_t_ + (kSlots - 1) * kSequenceS + 15 * kVlp16FiringPeriodS + kVlp16TransmitLatencyS);
  last_capture_t_ = packet->t_capture_s;
  packets->push_back(std::move(*packet));
  slots_.clear();
  anchor_t_ += kSlots * kSequenceS;
  anchor_observed_ = false;
}

}  // namespace rotolidar::bench::rosmsg
