// Simulated VLP-16, beam footprint and echoes: mixed edge points, dual returns, glass transmission, pose
// interpolation and pose-query bounds, and the position packet source.
#include <algorithm>
#include <cmath>
#include <iostream>

#include <gtest/gtest.h>

#include "sim/lidar/position_source.hpp"
#include "sim/lidar/vlp16_caster.hpp"
#include "tests/sim/lidar/lidar_fixtures.hpp"
#include "tests/sim/world/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

using namespace lidar_test;

// ---------------------------------------------------------------------------------------------------------------
// Beam footprint and echoes.

TEST(Vlp16Beam, PatternWeightsAreAGaussianSpot) {
  EXPECT_EQ(BeamPattern(0).size(), 1u);
  for (int rings = 1; rings <= 4; ++rings) {
    const std::vector<BeamSample> p = BeamPattern(rings);
    ASSERT_EQ(p.size(), static_cast<std::size_t>(1 + 3 * rings * (rings + 1)));
    double total = 0.0, mx = 0.0, my = 0.0;
    for (const BeamSample& b : p) {
      total += b.weight, mx += b.weight * b.x, my += b.weight * b.y;
      EXPECT_LE(std::hypot(b.x, b.y), 1.0 + 1e-12);
    }
    EXPECT_NEAR(total, 1.0, 1e-12);
    EXPECT_NEAR(mx, 0.0, 1e-12);  // centred on the central ray
    EXPECT_NEAR(my, 0.0, 1e-12);
    EXPECT_GT(p.front().weight, p.back().weight);  // the profile falls off outwards
  }
}

TEST(Vlp16Beam, CloseReturnsMergeIntoAMixedPoint) {
  std::vector<SurfaceReturn> r = {{3.4, 0.2, false}, {3.0, 0.6, false}, {9.0, 0.0, false}};  // zero power: ignored
  std::vector<Echo> echoes;
  FormEchoes(r.data(), r.size(), 1.0, &echoes);
  ASSERT_EQ(echoes.size(), 1u);
  EXPECT_NEAR(echoes[0].range_m, (3.0 * 0.6 + 3.4 * 0.2) / 0.8, 1e-12);  // between the two surfaces
  EXPECT_NEAR(echoes[0].power, 0.8, 1e-12);
  r = {{3.0, 0.6, false}, {5.0, 0.2, false}};
  echoes.clear();
  FormEchoes(r.data(), r.size(), 1.0, &echoes);
  ASSERT_EQ(echoes.size(), 2u);  // >= 1 m apart: two echoes
  EXPECT_EQ(echoes[0].range_m, 3.0);
  EXPECT_EQ(echoes[1].range_m, 5.0);
}

TEST(Vlp16Beam, ModesPickStrongestLastAndDualAsTheManualSays) {
  const std::vector<Echo> near_strong = {{3.0, 0.6, false}, {5.0, 0.2, false}};
  EchoChoice c = ChooseEchoes(near_strong, Vlp16ReturnMode::kStrongest, 1.0, 0.4, 100.0);
  EXPECT_EQ(c.primary, 0);
  c = ChooseEchoes(near_strong, Vlp16ReturnMode::kLast, 1.0, 0.4, 100.0);
  EXPECT_EQ(c.primary, 1);
  c = ChooseEchoes(near_strong, Vlp16ReturnMode::kDual, 1.0, 0.4, 100.0);
  EXPECT_EQ(c.primary, 1);    // even block: last
  EXPECT_EQ(c.secondary, 0);  // odd block: strongest
  // The strongest is also the last: the odd block carries the second strongest.
  const std::vector<Echo> far_strong = {{2.0, 0.05, false}, {4.0, 0.1, false}, {6.0, 0.7, false}};
  c = ChooseEchoes(far_strong, Vlp16ReturnMode::kDual, 1.0, 0.4, 100.0);
  EXPECT_EQ(c.primary, 2);
  EXPECT_EQ(c.secondary, 1);
  // One echo: both blocks identical. A retroreflector outranks a stronger-looking diffuse echo.
  c = ChooseEchoes({{4.0, 0.3, false}}, Vlp16ReturnMode::kDual, 1.0, 0.4, 100.0);
  EXPECT_EQ(c.primary, 0);
  EXPECT_EQ(c.secondary, 0);
  c = ChooseEchoes({{4.0, 0.9, false}, {7.0, 0.1, true}}, Vlp16ReturnMode::kStrongest, 1.0, 0.4, 100.0);
  EXPECT_EQ(c.primary, 1);
  // Below the intensity threshold or outside the range window: not detected.
  c = ChooseEchoes({{4.0, 0.005, false}, {0.2, 0.5, false}}, Vlp16ReturnMode::kDual, 1.0, 0.4, 100.0);
  EXPECT_EQ(c.primary, -1);
  EXPECT_EQ(c.secondary, -1);
}

/// A 3 m high plate (albedo 0.5) at x = 3 m covering y in [0, 2], in front of an 8 m high wall (0.8) at x = wall_x_m.
Scene PlateBeforeWall(double wall_x_m) {
  Scene scene;
  scene.name = "plate_before_wall";
  scene.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, 1, 3));
  scene.materials = {Material{"wall", 0.8, false, ""}, Material{"plate", 0.5, false, ""}};
  Primitive wall, plate;
  wall.type = plate.type = PrimitiveType::kQuad;
  wall.name = "wall", plate.name = "plate";
  wall.rpy_rad = plate.rpy_rad = Eigen::Vector3d(0.0, -M_PI / 2, 0.0);  // local x -> world z, normal along x
  wall.center_m = Eigen::Vector3d(wall_x_m, 0.0, 1.5);
  wall.size_m = Eigen::Vector3d(8.0, 40.0, 0.0);  // every laser that passes the plate meets the wall
  plate.center_m = Eigen::Vector3d(3.0, 1.0, 1.5);
  plate.size_m = Eigen::Vector3d(3.0, 2.0, 0.0);
  plate.material_id = 1;
  scene.primitives = {wall, plate};
  return scene;
}

/// Fires two revolutions (600 rpm) from a static head at (0, 0, 1.5); returns sequences and truth.
void FireTwoRevolutions(const EmbreeScene& es, const Vlp16CasterConfig& config, std::vector<Vlp16FiringSequence>* seqs,
                        std::vector<LidarTruthPoint>* truth) {
  Vlp16Caster caster(es, LidarIntrinsics{}, config, 7);
  caster.Fire(3617, [](Seconds) { return Static({0.0, 0.0, 1.5}); }, seqs, truth);
}

// A spot straddling the plate's vertical edges: 0.4 m behind it the wall's return merges into a mixed range
// between the two surfaces; with the central ray alone every range is on a surface.
TEST(Vlp16Caster, DivergentBeamGivesMixedEdgePoints) {
  const auto es = testing::MakeEmbree(PlateBeforeWall(3.4));
  for (int rings : {0, 2}) {
    Vlp16CasterConfig config = NoiseFree();
    config.beam_rings = rings;
    std::vector<Vlp16FiringSequence> seqs;
    std::vector<LidarTruthPoint> truth;
    FireTwoRevolutions(*es, config, &seqs, &truth);
    int mixed = 0, on_plate = 0;
    for (std::size_t r = 0; r < truth.size(); ++r) {
      const LidarTruthPoint& t = truth[r];
      if (!t.returned || t.dir_world.x() <= 0.5) continue;  // the plate/wall side only
      const double x_m = t.origin_world.x() + t.echo_range_m[0] * t.dir_world.x();  // depth of the point
      if (std::abs(x_m - 3.0) < 1e-4) ++on_plate;
      // Between the surfaces by more than the float error (and the 2 mm code, checked on the wire below).
      if (x_m > 3.0 + 0.01 && x_m < 3.4 - 0.01) {
        ++mixed;
        EXPECT_NEAR(seqs[r / 16].distance_2mm[r % 16] * 0.002, t.echo_range_m[0], 0.001);
      }
    }
    EXPECT_GT(on_plate, 1000);
    if (rings == 0) {
      EXPECT_EQ(mixed, 0);
    }
    // Two edges x 16 lasers x 2 revolutions, 0.2 deg steps against a 0.17 deg wide spot: about one straddling
    // firing per laser and edge pass, fewer where the mix lands within 1 cm of a surface (measured 57).
    if (rings == 2) {
      EXPECT_GT(mixed, 20) << "mixed points";
    }
    std::cout << "beam_rings " << rings << ": " << mixed << " mixed edge points\n";
  }
}

// 2 m behind the plate the wall's part of a straddling spot is a separate echo: dual mode reports both.
TEST(Vlp16Caster, DualReturnReportsBothEchoesAtEdges) {
  const auto es = testing::MakeEmbree(PlateBeforeWall(5.0));
  Vlp16CasterConfig config = NoiseFree();
  config.beam_rings = 2;
  config.return_mode = Vlp16ReturnMode::kDual;
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  FireTwoRevolutions(*es, config, &seqs, &truth);
  int two_echoes = 0, single = 0;
  for (std::size_t r = 0; r < truth.size(); ++r) {
    const uint16_t last = seqs[r / 16].distance_2mm[r % 16], other = seqs[r / 16].distance2_2mm[r % 16];
    if (last == 0) continue;
    ASSERT_NE(other, 0u);  // a return in the even block always has one in the odd block
    if (last == other) {
      ++single;
      continue;
    }
    ++two_echoes;
    EXPECT_GT(last, other);  // even block = last = the farther echo (the wall), odd = the plate
    const double x_last = truth[r].origin_world.x() + truth[r].echo_range_m[0] * truth[r].dir_world.x();
    const double x_other = truth[r].origin_world.x() + truth[r].echo_range_m[1] * truth[r].dir_world.x();
    EXPECT_NEAR(x_last, 5.0, 0.02);  // a spot 0.17 deg wide: sub-ray depths differ by < 1 cm on one plane
    EXPECT_NEAR(x_other, 3.0, 0.02);
  }
  EXPECT_GT(single, 10000);
  EXPECT_GT(two_echoes, 20);  // measured 58: about one per laser and edge pass, as for the mixed points
  std::cout << two_echoes << " firings with two echoes, " << single << " with one\n";
}

// Glass 2 m ahead of a wall: it reflects 5 % and passes 90 %: the wall behind it is the strongest and last
// return, the pane the second strongest.
TEST(Vlp16Caster, TransmissiveGlassLetsTheWallBehindThrough) {
  Scene scene = PlateBeforeWall(5.0);
  scene.materials[1] = Material{"glass", 0.05, false, ""};
  const auto es = testing::MakeEmbree(scene);
  for (Vlp16ReturnMode mode : {Vlp16ReturnMode::kStrongest, Vlp16ReturnMode::kLast, Vlp16ReturnMode::kDual}) {
    for (double transmittance : {0.0, 0.9}) {
      Vlp16CasterConfig config = NoiseFree();
      config.return_mode = mode;
      if (transmittance > 0.0) config.material_transmittance = {{"glass", transmittance}};
      std::vector<Vlp16FiringSequence> seqs;
      std::vector<LidarTruthPoint> truth;
      FireTwoRevolutions(*es, config, &seqs, &truth);
      int behind_glass = 0;
      for (std::size_t r = 0; r < truth.size(); ++r) {
        const LidarTruthPoint& t = truth[r];
        if (!t.hit || std::abs(t.p_world.x() - 3.0) > 1e-4) continue;  // central ray on the pane
        ++behind_glass;
        const double to_wall_m = t.true_range_m * 5.0 / 3.0;  // same ray, plane at x = 5 instead of 3
        const double d0 = seqs[r / 16].distance_2mm[r % 16] * 0.002, d1 = seqs[r / 16].distance2_2mm[r % 16] * 0.002;
        const double expected0 = transmittance > 0.0 ? to_wall_m : t.true_range_m;
        EXPECT_NEAR(d0, expected0, 0.0011) << "mode " << int(mode) << " t " << transmittance;
        const double expected1 = mode == Vlp16ReturnMode::kDual ? t.true_range_m : expected0;
        EXPECT_NEAR(d1, expected1, 0.0011) << "mode " << int(mode) << " t " << transmittance;
        if (transmittance > 0.0) {  // the wall through glass twice: 0.81 x 0.8 x cos x exp(-0.004 r)
          const double cos_i = 3.0 / t.true_range_m;
          EXPECT_NEAR(seqs[r / 16].reflectivity[r % 16], 100 * 0.81 * 0.8 * cos_i * std::exp(-0.004 * to_wall_m), 1.0);
        }
      }
      EXPECT_GT(behind_glass, 1000);
    }
  }
  Vlp16CasterConfig bad = NoiseFree();
  bad.material_transmittance = {{"glass", 0.96}};  // 0.05 reflected + 0.96 passed > 1
  EXPECT_FALSE(CheckCasterMaterials(bad, scene.materials).ok);
  bad.material_transmittance = {{"no_such_material", 0.5}};
  const Status s = CheckCasterMaterials(bad, scene.materials);
  EXPECT_NE(s.message.find("no_such_material"), std::string::npos) << s.message;
}

// Interpolating the pose inside a 55 us sequence against calling the pose for every firing: the same rays to
// within float casting precision, for a head turning at 3 rad/s and moving at 2 m/s.
TEST(Vlp16Caster, InterpolatedPosesMatchPerFiringPoses) {
  const auto es = testing::MakeEmbree(testing::PlainRoom());
  const auto pose = [](Seconds t) {
    Pose3 T = Static({0.5 + 2.0 * t, -0.3, 1.2});
    T.linear() = (Eigen::AngleAxisd(3.0 * t, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(2.0 * t, Eigen::Vector3d::UnitX())).toRotationMatrix();
    return T;
  };
  std::vector<LidarTruthPoint> exact, interpolated;
  for (bool per_firing : {true, false}) {
    Vlp16CasterConfig config = NoiseFree();
    config.pose_per_firing = per_firing;
    Vlp16Caster caster(*es, LidarIntrinsics{}, config, 1);
    std::vector<Vlp16FiringSequence> seqs;
    caster.Fire(2000, pose, &seqs, per_firing ? &exact : &interpolated);
  }
  ASSERT_EQ(exact.size(), interpolated.size());
  double worst_m = 0.0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    worst_m = std::max(worst_m, (exact[i].p_world - interpolated[i].p_world).norm());
  }
  // Interpolation error ~ (w dt)^2 / 8 x range = (3.6 rad/s x 55 us)^2 / 8 x 6 m = 3e-8 m; float casting adds
  // ~1e-6 m at these coordinates.
  EXPECT_LT(worst_m, 1e-5);
  std::cout << "interpolated vs exact pose: worst hit difference " << worst_m << " m\n";
}

// The sim's physics trace covers a packet's firings only: the caster must never ask for a pose outside the
// firings of the current Fire call, and must ask in time order.
TEST(Vlp16Caster, PoseQueriesStayWithinEachCallsFirings) {
  const auto es = testing::MakeEmbree(testing::PlainRoom());
  for (bool per_firing : {false, true}) {
    Vlp16CasterConfig config = NoiseFree();
    config.pose_per_firing = per_firing;
    Vlp16Caster caster(*es, LidarIntrinsics{}, config, 1);
    std::vector<Vlp16FiringSequence> seqs;
    for (int call = 0; call < 50; ++call) {
      const int n = 1 + call % 40;  // batches of 32 and partial ones
      const Seconds first = caster.FiringTime(caster.sequences_fired(), 0);
      const Seconds last = caster.FiringTime(caster.sequences_fired() + n - 1, 15);
      std::vector<Seconds> asked;
      caster.Fire(n, [&](Seconds t) { asked.push_back(t); return Static({0.0, 0.0, 1.5}); }, &seqs, nullptr);
      ASSERT_FALSE(asked.empty());
      EXPECT_GE(asked.front(), first - 1e-12);
      EXPECT_LE(asked.back(), last + 1e-12);
      EXPECT_TRUE(std::is_sorted(asked.begin(), asked.end()));
      // One query per sequence start plus one at the last firing (or one per firing).
      EXPECT_EQ(asked.size(), static_cast<std::size_t>(per_firing ? 16 * n : n + 1));
    }
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Position packets.

// A free-running head's clock drift reaches the position packets' stamps too: sensor time = t - offset +
// D * 1e-6 * t (to the wire's 1 us), over 30 s (6 ms gained at 200 ppm); the host's capture time does not drift.
TEST(Vlp16PositionSource, FreeRunningClockDriftMovesTheStamps) {
  Vlp16PositionConfig config;
  config.pps_status = 0;
  config.gps_fix = false;
  config.lidar_clock_offset_s = -0.1;
  config.clock_drift_ppm = 200.0;
  Vlp16PositionSource source(config);
  std::vector<LidarPacket> packets;
  source.EmitUntil(30.0, &packets);
  ASSERT_GT(packets.size(), 1600u);
  for (std::size_t k = 0; k < packets.size(); ++k) {
    const double t = k / config.rate_hz;
    EXPECT_NEAR(packets[k].t_capture_s, t + config.transmit_latency_s, 1e-12);
    Vlp16PositionPacket fields;
    ASSERT_TRUE(ParseVlp16PositionPacket(packets[k].payload.data(), packets[k].payload.size(), &fields).ok);
    ASSERT_NEAR(double(fields.timestamp_us), (t + 0.1 + 200e-6 * t) * 1e6, 1.0) << k;
  }
}

TEST(Vlp16PositionSource, EmitsLockedUtcPacketsAtTheManualsRate) {
  Vlp16PositionConfig config;
  config.epoch_unix_s = 1709211600.0 - 0.4;  // 12:59:59.6 UTC: the stream crosses a UTC hour
  config.lidar_clock_offset_s = PpsLockedClockOffsetS(config.epoch_unix_s);
  std::string error;
  ASSERT_TRUE(config.Validate(&error)) << error;
  Vlp16PositionSource source(config);
  std::vector<LidarPacket> packets;
  EXPECT_EQ(source.EmitUntil(1.0, &packets), 54u);  // t = 0, 1/53.82, ... <= 1 s
  EXPECT_EQ(source.EmitUntil(1.0, &packets), 0u);   // nothing new
  Vlp16Decoder decoder(LidarIntrinsics{}, Vlp16DecoderConfig{});
  std::vector<LidarPoint> none;
  for (std::size_t k = 0; k < packets.size(); ++k) {
    const LidarPacket& p = packets[k];
    ASSERT_EQ(p.udp_port, kVlp16PositionPort);
    const double t = k / config.rate_hz;
    EXPECT_NEAR(p.t_capture_s, t + config.transmit_latency_s, 1e-12);
    Vlp16PositionPacket fields;
    ASSERT_TRUE(ParseVlp16PositionPacket(p.payload.data(), p.payload.size(), &fields).ok);
    EXPECT_EQ(fields.pps_status, 2);
    EXPECT_EQ(fields.timestamp_us, Vlp16TimestampUs(t, config.lidar_clock_offset_s));
    double utc_s = 0.0;
    ASSERT_TRUE(ParseGprmcUtc(fields.nmea, &utc_s).ok) << fields.nmea;
    EXPECT_EQ(utc_s, std::floor(config.epoch_unix_s + t));  // the last whole UTC second
    ASSERT_TRUE(decoder.Decode(p, &none).ok);
    // The sensor clock reads UTC past the hour: the decoder finds the hour of the packet's own UTC time.
    ASSERT_TRUE(decoder.hour_start_unix_s().has_value());
    EXPECT_EQ(*decoder.hour_start_unix_s(), std::floor((config.epoch_unix_s + t) / 3600.0) * 3600.0) << k;
  }
  config.lidar_clock_offset_s = 0.0;  // a sensor clock that does not read UTC cannot claim PPS lock
  EXPECT_FALSE(config.Validate(&error));
  EXPECT_NE(error.find("lidar_clock_offset_s"), std::string::npos) << error;
  config.pps_status = 0;
  EXPECT_TRUE(config.Validate(&error)) << error;
}


}  // namespace
}  // namespace rotolidar::sim
