// Free-space test (core/pipeline/free_space.hpp) on ray-cast scans of a room with a moving ball: the ball's
// points where it no longer is are seen through by later scans, arriving points by earlier ones, and the
// room's walls, floor and the ball's own current surface are not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "core/pipeline/estimator_internal.hpp"
#include "core/pipeline/free_space.hpp"
#include "tests/core/pipeline/room_scans.hpp"

namespace rotolidar {
namespace {

using test::kDeg;
using test::RoomRange;
using test::OnBall;
using test::Scan;

TEST(RangeImage, SeesThroughFreeSpaceNotSurfacesOrGrazingFloor) {
  const FreeSpaceConfig config;
  RangeImage image(config.bins_per_face, config.min_looked_bins);
  for (const ScanPoint& p : Scan(std::nullopt)) image.Add(p.p_base);
  const float margin = 0.1f;
  // In front of the +x wall (8 m): free; on it: hit; behind it: occluded, unknown.
  EXPECT_EQ(image.Judge({4.f, 0.3f, 0.2f}, margin), RangeImage::Verdict::kSeenThrough);
  EXPECT_EQ(image.Judge({8.f, 0.3f, 0.2f}, margin), RangeImage::Verdict::kHit);
  EXPECT_EQ(image.Judge({12.f, 0.45f, 0.3f}, margin), RangeImage::Verdict::kUnknown);
  // The floor 1.5 m below, 7 m away (12 deg grazing): the neighbouring bins hold nearer floor, so never free.
  EXPECT_NE(image.Judge({7.f, 0.5f, -1.5f}, margin), RangeImage::Verdict::kSeenThrough);
  // Straight down past the scan's -80 deg elevation: never looked at.
  EXPECT_EQ(image.Judge({0.05f, 0.02f, -1.f}, margin), RangeImage::Verdict::kUnknown);
}

/// One revolution of a VLP-16-like head (16 beams at -15..+15 deg, 0.2 deg azimuth steps) whose spin axis is
/// tilted 70 deg off z and turned 15 deg about z during the sweep, as on a rotor: a belt of the room.
std::vector<ScanPoint> RotaryBand() {
  std::vector<ScanPoint> points;
  for (double az = 0; az < 360; az += 0.2) {
    const Eigen::Matrix3d R = (Eigen::AngleAxisd((30.0 + 15.0 * az / 360.0) * kDeg, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(70.0 * kDeg, Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    for (double el = -15; el <= 15; el += 2.0) {
      const Eigen::Vector3d d = R * Eigen::Vector3d(std::cos(el * kDeg) * std::cos(az * kDeg),
                                                    std::cos(el * kDeg) * std::sin(az * kDeg), std::sin(el * kDeg));
      ScanPoint p;
      p.range_m = float(RoomRange(d));
      p.p_base = (p.range_m * d).cast<float>();
      points.push_back(p);
    }
  }
  return points;
}

// Sealing bounds the band of directions that hold returns; Judge must then give exactly the verdicts it gives
// unsealed (the bound only skips directions whose 3x3 bins are all empty), on a rotary belt and on the whole
// sphere (no bound). Queries: random directions at 0.3-1.2x the room's range there, so that hits, seen-through
// and occluded points all occur.
TEST(RangeImage, SealedBandGivesTheSameVerdicts) {
  const FreeSpaceConfig config;
  for (const bool belt : {true, false}) {
    RangeImage open(config.bins_per_face, config.min_looked_bins), sealed = open;
    for (const ScanPoint& p : belt ? RotaryBand() : Scan(std::nullopt)) {
      open.Add(p.p_base);
      sealed.Add(p.p_base);
    }
    sealed.Seal();
    // A belt of +-15 deg (smeared by the 15 deg rotor turn) leaves most of the sphere out; the room scan's
    // +-80 deg elevations leave only the caps around its poles out.
    if (belt) {
      EXPECT_LT(sealed.band_sin(), 0.6f);
      EXPECT_GT(std::abs(sealed.band_axis().dot(Eigen::Vector3f(0, -std::sin(70 * kDeg), std::cos(70 * kDeg)))),
                0.8f);
    } else {
      EXPECT_GT(sealed.band_sin(), std::sin(80 * kDeg));
    }
    std::mt19937 rng(7);
    std::normal_distribution<double> gauss;
    std::uniform_real_distribution<double> scale(0.3, 1.2);
    int counts[3] = {0, 0, 0}, outside = 0;
    for (int i = 0; i < 200000; ++i) {
      const Eigen::Vector3d d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
      const Eigen::Vector3f q = (scale(rng) * RoomRange(d) * d).cast<float>();
      const RangeImage::Verdict v = sealed.Judge(q, 0.1f, 0.01f);
      ASSERT_EQ(v, open.Judge(q, 0.1f, 0.01f)) << "direction " << d.transpose();
      ++counts[int(v)];
      const float c = q.normalized().dot(sealed.band_axis());
      outside += c * c > sealed.band_sin() * sealed.band_sin() ? 1 : 0;
    }
    EXPECT_GT(counts[int(RangeImage::Verdict::kHit)], 1000);
    EXPECT_GT(counts[int(RangeImage::Verdict::kSeenThrough)], 10000);
    if (belt) {
      EXPECT_GT(outside, 200000 / 3) << "directions the bound decides";
    }
  }
}

// The ball stands at A for 1 s, then at B: its points at A are dynamic (later scans see through A, however
// long it stood), the room is not, and the ball's points at B are arrivals (earlier scans saw through B).
TEST(FreeSpaceFilter, KeepsMovedBallOutAndRoomIn) {
  FreeSpaceConfig config;
  config.delay_s = 1.5;
  config.window_s = 1.5;
  FreeSpaceFilter filter(config, Eigen::Vector3d::Zero());
  const Eigen::Vector3d a(3.0, 1.0, 0.0), b(-2.0, -2.5, 0.5);
  size_t ball_a = 0, room = 0, ball_a_accepted = 0;
  size_t judged = 0, dynamic = 0;
  for (int k = 0; k < 25; ++k) {
    const double t = 0.1 * k;
    const Eigen::Vector3d ball = t < 1.0 ? a : b;
    filter.AddScan(t, Pose3::Identity(), Scan(ball), 40.0);
    if (k == 10 || k == 11) {  // just arrived at B: earlier scans saw through B (and through nothing of the room)
      EXPECT_TRUE(filter.SeenThroughBefore(t + 0.05, b - 0.3 * b.normalized()));  // the ball's near side
      EXPECT_FALSE(filter.SeenThroughBefore(t + 0.05, Eigen::Vector3d(8.0, 0.5, 0.5)));
    }
    const FreeSpaceCounts c = filter.Release(
        k == 24, [](const Eigen::Vector3d&) { return true; },
        [&](const Eigen::Vector3d& p) {
          if (OnBall(p, a)) ++ball_a_accepted;
        });
    judged += c.judged;
    dynamic += c.dynamic;
  }
  for (int k = 0; k < 10; ++k)
    for (const ScanPoint& p : Scan(a)) (OnBall(p.p_base.cast<double>(), a) ? ball_a : room) += 1;
  ASSERT_GT(ball_a, 1000u);
  EXPECT_EQ(ball_a_accepted, 0u) << "of " << ball_a << " points on the ball at A";
  // Every point of the 25 scans was judged; the dynamic ones are the ball at A plus, at most, a sliver of the
  // room's edges around the ball's outline (a 3x3 neighbourhood straddles the ball and the wall behind it).
  EXPECT_EQ(judged, 25u * Scan(std::nullopt).size());
  EXPECT_GE(dynamic, ball_a);
  EXPECT_LT(dynamic - ball_a, room / 1000) << "room points called dynamic";
}

// The registration-side screen (Estimator::ScreenMovingFeatures): of a new scan's cloud, the points standing where
// earlier scans saw free space (the ball that just arrived at B) are dropped at the cloud's pose; the room's
// points stay. The rig stands at a pose off the world origin, so a frame mix-up would misjudge the room.
// An image prepared ahead of AddScan (PrepareImage) is the one AddScan would build: the same verdicts; and one
// prepared for other points is not taken.
TEST(FreeSpaceFilter, APreparedImageGivesTheSameVerdicts) {
  const Eigen::Vector3d a(3.0, 1.0, 0.0), b(-2.0, -2.5, 0.5);
  FreeSpaceFilter built(FreeSpaceConfig(), Eigen::Vector3d::Zero());
  FreeSpaceFilter prepared(FreeSpaceConfig(), Eigen::Vector3d::Zero());
  const std::vector<ScanPoint> with_a = Scan(a), with_b = Scan(b);
  built.AddScan(0.0, Pose3::Identity(), with_a, 40.0);
  prepared.PrepareImage(with_a);
  prepared.AddScan(0.0, Pose3::Identity(), with_a, 40.0);
  std::vector<ScanPoint> other(with_a.begin(), with_a.end() - 1);
  prepared.PrepareImage(other);  // not the points AddScan gets next (another count): it builds its own
  built.AddScan(0.1, Pose3::Identity(), with_b, 40.0);
  prepared.AddScan(0.1, Pose3::Identity(), with_b, 40.0);
  Eigen::Matrix3Xf probe(3, 2 * Eigen::Index(with_a.size()));
  for (size_t i = 0; i < with_a.size(); ++i) {
    probe.col(Eigen::Index(i)) = 0.8f * with_a[i].p_base;  // in front of the first scan's returns
    probe.col(Eigen::Index(with_a.size() + i)) = 0.8f * with_b[i].p_base;
  }
  std::vector<uint8_t> seen_built, seen_prepared;
  built.SeenThroughBefore(0.2, probe, &seen_built);
  prepared.SeenThroughBefore(0.2, probe, &seen_prepared);
  EXPECT_EQ(seen_built, seen_prepared);
  EXPECT_GT(std::count(seen_built.begin(), seen_built.end(), 1), 1000);
}

TEST(DropSeenThrough, DropsArrivalsKeepsTheRoom) {
  FreeSpaceFilter filter(FreeSpaceConfig(), Eigen::Vector3d::Zero());
  Pose3 T_world_base = Pose3::Identity();
  T_world_base.translate(Eigen::Vector3d(4.0, -2.0, 0.3)).rotate(Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d a(3.0, 1.0, 0.0), b(-2.0, -2.5, 0.5);
  for (int k = 0; k < 10; ++k) filter.AddScan(0.1 * k, T_world_base, Scan(a), 40.0);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  size_t on_b = 0;
  for (const ScanPoint& p : Scan(b)) {
    if (OnBall(p.p_base.cast<double>(), a)) continue;  // where the ball was: uncertain (hidden, then not)
    pcl::PointXYZI q;
    q.x = p.p_base.x(), q.y = p.p_base.y(), q.z = p.p_base.z();
    cloud.push_back(q);
    on_b += OnBall(p.p_base.cast<double>(), b) ? 1 : 0;
  }
  const size_t before = cloud.size();
  ASSERT_GT(on_b, 100u);
  // The same cloud in two pieces, judged in one pass: each piece keeps what the whole keeps, in order.
  pcl::PointCloud<pcl::PointXYZI> first, second;
  for (size_t i = 0; i < before; ++i) (i < before / 3 ? first : second).push_back(cloud[i]);
  const size_t dropped_in_pieces = DropSeenThrough(filter, 1.0, T_world_base, {&first, &second});
  const size_t dropped = DropSeenThrough(filter, 1.0, T_world_base, {&cloud});
  EXPECT_EQ(dropped_in_pieces, dropped);
  ASSERT_EQ(first.size() + second.size(), cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const pcl::PointXYZI& q = i < first.size() ? first[i] : second[i - first.size()];
    EXPECT_EQ(q.x, cloud[i].x) << i;
  }
  EXPECT_EQ(cloud.size(), before - dropped);
  size_t b_kept = 0;
  for (const pcl::PointXYZI& q : cloud) b_kept += OnBall(Eigen::Vector3d(q.x, q.y, q.z), b) ? 1 : 0;
  // Every arrival goes; of the room at most the sliver around the ball's outline that shares a 3x3 bin
  // neighbourhood with the ball (as for KeepsMovedBallOutAndRoomIn).
  EXPECT_EQ(b_kept, 0u) << "of " << on_b;
  EXPECT_LT(dropped - on_b, (before - on_b) / 1000) << "room points dropped";
  // At the wrong pose (the rig 1 m aside) walls stand where space was seen free: the screen is pose-sensitive.
  Pose3 T_wrong = T_world_base;
  T_wrong.translate(Eigen::Vector3d(0.0, 1.0, 0.0));
  pcl::PointCloud<pcl::PointXYZI> again = cloud;
  EXPECT_GT(DropSeenThrough(filter, 1.0, T_wrong, {&again}), 1000u);
}

TEST(FreeSpaceConfig, ValidateNamesTheField) {
  FreeSpaceConfig c;
  std::string why;
  EXPECT_TRUE(c.Validate(&why));
  c.bins_per_face = 1;
  EXPECT_FALSE(c.Validate(&why));
  EXPECT_NE(why.find("bins_per_face"), std::string::npos);
}

}  // namespace
}  // namespace rotolidar
