// Curvature features (core/features/curvature_features.hpp) on synthetic VLP-16 scans cast into known geometry
// (box rooms, a pillar in front of a wall, a corridor), and optionally on real VLP-16 packets ($ROTOLIDAR_DATA).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>

#include "core/features/curvature_features.hpp"
#include "core/io/pcap.hpp"
#include "core/io/scan_splitter.hpp"
#include "core/io/vlp16.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Box {
  Eigen::Vector3d lo, hi;
};

// Distance along unit ray d from the origin (inside `room`) to the room's inner surface.
double ExitDistance(const Box& room, const Eigen::Vector3d& d) {
  double t = kInf;
  for (int a = 0; a < 3; ++a) {
    if (d[a] > 1e-12) t = std::min(t, room.hi[a] / d[a]);
    if (d[a] < -1e-12) t = std::min(t, room.lo[a] / d[a]);
  }
  return t;
}

// Distance along unit ray d from the origin (outside `box`) to the solid box, kInf when missed (slab method).
double EntryDistance(const Box& box, const Eigen::Vector3d& d) {
  double t_in = 0.0, t_out = kInf;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (box.lo[a] > 0.0 || box.hi[a] < 0.0) return kInf;
      continue;
    }
    double t0 = box.lo[a] / d[a], t1 = box.hi[a] / d[a];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0), t_out = std::min(t_out, t1);
  }
  return t_in <= t_out ? t_in : kInf;
}

struct Scene {
  Box room;
  std::vector<Box> solids;
  double noise_sigma_m = 0.0;
  double az_step_deg = 0.2;  // 600 rpm
};

// One VLP-16 revolution from the origin (lidar = base frame): 16 rings at -15..15 deg, azimuth 0..360 deg.
std::vector<ScanPoint> CastScan(const Scene& scene, uint64_t seed = 1) {
  RandomStream rng(seed, "features_test.range_noise");
  std::vector<ScanPoint> pts;
  const int sequences = static_cast<int>(std::lround(360.0 / scene.az_step_deg));
  for (int k = 0; k < sequences; ++k) {
    const double az_deg = k * scene.az_step_deg;
    for (int ring = 0; ring < 16; ++ring) {
      const Eigen::Vector3d d = Vlp16RayDirection((-15.0 + 2.0 * ring) * kDeg, az_deg * kDeg);
      double t = ExitDistance(scene.room, d);
      for (const Box& b : scene.solids) t = std::min(t, EntryDistance(b, d));
      const double r = t + scene.noise_sigma_m * rng.Normal();
      ScanPoint p;
      p.p_base = (d * r).cast<float>();
      p.range_m = static_cast<float>(r);
      p.azimuth_deg = static_cast<float>(az_deg);
      p.ring = static_cast<uint8_t>(ring);
      p.t_s = k * kVlp16SequencePeriodS + ring * kVlp16FiringPeriodS;
      pts.push_back(p);
    }
  }
  return pts;
}

// A tall box room: no ring reaches floor or ceiling (15 deg rise over 7.8 m < 10 m), so its only edges are the
// four vertical corners.
Scene TallRoom() {
  Scene s;
  s.room = {{-6.0, -5.0, -10.0}, {4.0, 3.0, 10.0}};
  return s;
}

double DistanceToNearestCorner(const Box& room, const Eigen::Vector3f& p) {
  double best = kInf;
  for (const double x : {room.lo.x(), room.hi.x()})
    for (const double y : {room.lo.y(), room.hi.y()}) best = std::min(best, std::hypot(p.x() - x, p.y() - y));
  return best;
}

double DistanceToWall(const Box& room, const Eigen::Vector3f& p) {
  return std::min({std::abs(p.x() - room.lo.x()), std::abs(p.x() - room.hi.x()), std::abs(p.y() - room.lo.y()),
                   std::abs(p.y() - room.hi.y())});
}

// (ring, sector) -> count of points with the given labels.
std::map<std::pair<int, int>, int> CountPerCell(const std::vector<ScanPoint>& pts, const FeatureResult& r,
                                                const std::vector<FeatureLabel>& which, int sectors) {
  std::map<std::pair<int, int>, int> counts;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (const FeatureLabel l : which)
      if (r.labels[i] == l) ++counts[{pts[i].ring, int(pts[i].azimuth_deg / (360.0 / sectors))}];
  return counts;
}

TEST(RingCurvature, MatchesEq3OnLineAndRightAngleCorner) {
  // Points every d = 2 cm along a straight line, then a right-angle corner at index 10, 5 m from the origin.
  const float d = 0.02f;
  std::vector<ScanPoint> ring;
  for (int i = 0; i < 21; ++i) {
    ScanPoint p;
    p.p_base = i <= 10 ? Eigen::Vector3f(5.f, -d * (10 - i), 0.f) : Eigen::Vector3f(5.f - d * (i - 10), 0.f, 0.f);
    p.range_m = p.p_base.norm();
    p.azimuth_deg = 0.2f * i;
    ring.push_back(p);
  }
  const std::vector<float> c = RingCurvature(ring, 5, 1.0);
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(std::isnan(c[i]) && std::isnan(c[20 - i])) << i;  // no full window
  EXPECT_NEAR(c[5], 0.f, 1e-6f);  // straight line: the sum cancels
  // Apex: sum = -d (1+..+5) (u + v), |u + v| = sqrt(2): c = 15 sqrt(2) d / (10 * 5 m).
  EXPECT_NEAR(c[10], 15.0 * std::sqrt(2.0) * d / (10.0 * 5.0), 1e-6);
  // An azimuth gap inside the window removes the curvature.
  ring[12].azimuth_deg += 5.f;
  for (int i = 12; i < 21; ++i) ring[i].azimuth_deg += 5.f;
  const std::vector<float> gapped = RingCurvature(ring, 5, 1.0);
  EXPECT_TRUE(std::isnan(gapped[10]));
  EXPECT_FALSE(std::isnan(gapped[6]));  // window 1..11 has no gap
}

TEST(ExtractFeatures, EdgesAtRoomCornersPlanarOnWalls) {
  const Scene scene = TallRoom();
  const std::vector<ScanPoint> pts = CastScan(scene);
  const FeatureResult r = ExtractFeatures(pts, 0.0, FeatureConfig());
  ASSERT_GT(r.features.edge.size(), 0u);
  ASSERT_GT(r.features.planar.size(), 0u);
  double worst_edge = 0.0, closest_planar = kInf;
  for (const auto& p : r.features.edge) worst_edge = std::max(worst_edge, DistanceToNearestCorner(scene.room, p.getVector3fMap()));
  for (const auto& p : r.features.planar) {
    closest_planar = std::min(closest_planar, DistanceToNearestCorner(scene.room, p.getVector3fMap()));
    EXPECT_LT(DistanceToWall(scene.room, p.getVector3fMap()), 1e-3);
  }
  std::printf("edges %zu planar %zu less_sharp %zu less_flat %zu/%zu worst edge %.4f closest planar %.4f\n",
              r.features.edge.size(), r.features.planar.size(), r.features.less_sharp.size(),
              r.stats.num_less_flat, r.stats.num_less_flat_raw, worst_edge, closest_planar);
  EXPECT_LT(worst_edge, 0.05);
  EXPECT_GT(closest_planar, 0.1);
  // Every ring finds every corner.
  for (int ring = 0; ring < 16; ++ring) {
    int corners = 0;
    for (const double x : {scene.room.lo.x(), scene.room.hi.x()})
      for (const double y : {scene.room.lo.y(), scene.room.hi.y()}) {
        bool found = false;
        for (std::size_t i = 0; i < pts.size(); ++i)
          found |= pts[i].ring == ring && r.labels[i] == FeatureLabel::kEdge &&
                   std::hypot(pts[i].p_base.x() - x, pts[i].p_base.y() - y) < 0.05;
        corners += found;
      }
    EXPECT_EQ(corners, 4) << "ring " << ring;
  }
}

}  // namespace
}  // namespace rotolidar
namespace rotolidar { namespace {
TEST(Experiment, Noise) {
  for (double sigma : {0.0, 0.005, 0.01, 0.02, 0.03}) {
    Scene scene = TallRoom();
    scene.noise_sigma_m = sigma;
    const std::vector<ScanPoint> pts = CastScan(scene);
    const FeatureResult r = ExtractFeatures(pts, 0.0, FeatureConfig());
    int good = 0, bad = 0; int corners_found = 0;
    for (const auto& p : r.features.edge) (DistanceToNearestCorner(scene.room, p.getVector3fMap()) < 0.1 ? good : bad)++;
    double closest_planar = kInf;
    for (const auto& p : r.features.planar) closest_planar = std::min(closest_planar, DistanceToNearestCorner(scene.room, p.getVector3fMap()));
    std::printf("sigma %.3f edges %zu (at corners %d, elsewhere %d) planar %zu closest planar %.3f beamparallel %zu occl %zu lessflat %zu\n", sigma, r.features.edge.size(), good, bad, r.features.planar.size(), closest_planar, r.stats.num_beam_parallel, r.stats.num_occluded, r.stats.num_less_flat_raw);
  }
}
}}
namespace rotolidar { namespace {
TEST(Experiment, Real) {
  std::vector<LidarPacket> packets;
  ASSERT_TRUE(ReadRawVlp16Payloads("/work/shared/data/vlp16_einride/recording.bin", &packets).ok);
  Vlp16Decoder decoder{LidarIntrinsics(), Vlp16DecoderConfig()};
  std::vector<LidarPoint> points;
  for (auto& p : packets) decoder.Decode(p, &points);
  RevolutionSplitter splitter(0.0);
  std::vector<LidarScan> scans;
  splitter.Add(points, &scans);
  for (int si : {1, 5}) {
  const LidarScan& scan = scans[si];
  std::vector<Eigen::Vector3d> p;
  for (auto& lp : scan.points) p.emplace_back(lp.x_m, lp.y_m, lp.z_m);
  std::vector<ScanPoint> sp = MakeScanPoints(scan, p);
  PreprocessConfig pc; 
  for (double mul : {1.0, 2.0, 3.0}) { for (int k : {10, 20, 50}) { pc.sor_std_mul = mul; pc.sor_k = k; auto pr = Preprocess(sp, pc);

    std::printf("sor k %d mul %.1f: in %zu range-removed %zu sor-removed %zu\n", k, mul, pr.num_input, pr.removed_range, pr.removed_sor); } }
  pc = PreprocessConfig();
  for (double mul : {2.0, 3.0}) for (bool norm : {false, true}) {
    std::vector<ScanPoint> v = sp; RangeFilter(0.8, 60, &v);
    std::vector<ScanPoint> w = v; StatisticalOutlierFilter(20, mul, norm, &w);
    std::map<int,int> all, kept;
    for (auto& a : v) all[int(a.range_m)]++;
    for (auto& a : w) kept[int(a.range_m)]++;
    std::printf("mul %.1f norm %d removed %zu by range bin:", mul, int(norm), v.size() - w.size());
    for (auto& [b, n] : all) std::printf(" %dm:%d/%d", b, n - kept[b], n);
    std::printf("\n");
  }
  auto pr = Preprocess(sp, pc);
  FeatureConfig fc;
  auto r = ExtractFeatures(pr.points, 0.0, fc);
  std::vector<double> cr, cc; std::vector<double> steps;
  for (size_t i = 0; i < pr.points.size(); ++i) if (!std::isnan(r.curvature[i])) { cr.push_back(r.curvature[i] * pr.points[i].range_m); cc.push_back(r.curvature[i]); }
  std::sort(cr.begin(), cr.end()); std::sort(cc.begin(), cc.end());
  auto q = [&](std::vector<double>& v, double f) { return v[size_t(f * (v.size() - 1))]; };
  std::printf("c*r quantiles 10%% %.4f 25%% %.4f 50%% %.4f 75%% %.4f 90%% %.4f\n", q(cr,.1), q(cr,.25), q(cr,.5), q(cr,.75), q(cr,.9));
  std::printf("c quantiles 10%% %.5f 25%% %.5f 50%% %.5f 75%% %.5f 90%% %.5f\n", q(cc,.1), q(cc,.25), q(cc,.5), q(cc,.75), q(cc,.9));
  std::printf("stats in %zu invalid %zu nowin %zu occl %zu par %zu edge %zu planar %zu lsharp %zu lflat %zu/%zu\n", r.stats.num_input, r.stats.num_invalid, r.stats.num_no_window, r.stats.num_occluded, r.stats.num_beam_parallel, r.stats.num_edge, r.stats.num_planar, r.stats.num_less_sharp, r.stats.num_less_flat, r.stats.num_less_flat_raw);
  // azimuth steps per ring
  std::map<int, std::vector<float>> az;
  for (auto& p2 : pr.points) az[p2.ring].push_back(p2.azimuth_deg);
  }
}
}}
