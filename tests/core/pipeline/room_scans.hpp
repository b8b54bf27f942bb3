#pragma once
// Ray-cast test scans shared by the free-space tests: a room around a sensor at the origin, with a ball that
// can stand anywhere in it.
#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/types/scan_point.hpp"

namespace rotolidar::test {

inline constexpr double kDeg = M_PI / 180.0;

/// Room: the box [-8, 8] x [-5, 5] x [-1.5, 2.5] around the sensor at the origin.
inline double RoomRange(const Eigen::Vector3d& d) {
  const Eigen::Vector3d lo(-8, -5, -1.5), hi(8, 5, 2.5);
  double t = 1e9;
  for (int a = 0; a < 3; ++a) {
    if (d[a] > 1e-12) t = std::min(t, hi[a] / d[a]);
    if (d[a] < -1e-12) t = std::min(t, lo[a] / d[a]);
  }
  return t;
}

/// Ray from the origin along unit d against a ball (centre c, radius r): the entry distance, if hit.
inline std::optional<double> BallRange(const Eigen::Vector3d& d, const Eigen::Vector3d& c, double r) {
  const double b = d.dot(c), disc = b * b - (c.squaredNorm() - r * r);
  if (disc < 0 || b - std::sqrt(disc) <= 0) return std::nullopt;
  return b - std::sqrt(disc);
}

/// One scan: rays every 0.5 deg of azimuth and 1 deg of elevation, the ball (if any) in front of the room.
inline std::vector<ScanPoint> Scan(const std::optional<Eigen::Vector3d>& ball) {
  std::vector<ScanPoint> points;
  for (double el = -80; el <= 80; el += 1.0)
    for (double az = 0; az < 360; az += 0.5) {
      const Eigen::Vector3d d(std::cos(el * kDeg) * std::cos(az * kDeg), std::cos(el * kDeg) * std::sin(az * kDeg),
                              std::sin(el * kDeg));
      double r = RoomRange(d);
      if (ball)
        if (auto rb = BallRange(d, *ball, 0.3)) r = std::min(r, *rb);
      ScanPoint p;
      p.p_base = (r * d).cast<float>();
      p.range_m = float(r);
      points.push_back(p);
    }
  return points;
}

inline bool OnBall(const Eigen::Vector3d& p, const Eigen::Vector3d& c) { return std::abs((p - c).norm() - 0.3) < 0.01; }

}  // namespace rotolidar::test
