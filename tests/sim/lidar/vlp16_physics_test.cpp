// Simulated VLP-16 range physics beyond constant Gaussian noise: range-, incidence- and reflectivity-dependent
// noise, range walk, mirrors, retroreflector blooming, the realism presets and determinism.
#include <cmath>
#include <iostream>
#include <vector>

#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include "sim/lidar/lidar_realism.hpp"
#include "sim/sim_config.hpp"
#include "sim/lidar/vlp16_caster.hpp"
#include "tests/sim/lidar/lidar_fixtures.hpp"
#include "tests/sim/world/world_fixtures.hpp"

namespace rotolidar::sim {
namespace {

using namespace lidar_test;

/// A vertical quad facing -x at x = x_m (local x -> world z), centre height 1.5 m.
Primitive WallAt(const std::string& name, double x_m, double y_m, double width_m, double height_m, int material) {
  Primitive p;
  p.type = PrimitiveType::kQuad;
  p.name = name;
  p.rpy_rad = Eigen::Vector3d(0.0, -M_PI / 2, 0.0);
  p.center_m = Eigen::Vector3d(x_m, y_m, 1.5);
  p.size_m = Eigen::Vector3d(height_m, width_m, 0.0);
  p.material_id = material;
  return p;
}

Scene OneWall(double albedo) {
  Scene scene;
  scene.name = "one_wall";
  scene.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, 1, 3));
  scene.materials = {Material{"wall", albedo, false, ""}};
  scene.primitives = {WallAt("wall", 5.0, 0.0, 40.0, 8.0, 0)};
  return scene;
}

/// Two revolutions (600 rpm) from a static head at (0, 0, 1.5).
void Fire(const EmbreeScene& es, const Vlp16CasterConfig& config, uint64_t seed, std::vector<Vlp16FiringSequence>* seqs,
          std::vector<LidarTruthPoint>* truth) {
  Vlp16Caster caster(es, LidarIntrinsics{}, config, seed);
  caster.Fire(3617, [](Seconds) { return Static({0.0, 0.0, 1.5}); }, seqs, truth);
}

double Reported(const std::vector<Vlp16FiringSequence>& seqs, std::size_t r) {
  return seqs[r / 16].distance_2mm[r % 16] * kVlp16DistanceUnitM;
}

// Every factor of the noise model at once: the errors divided by the model's sigma for each firing (range,
// incidence on the wall, power of the echo) have unit standard deviation in every part of the wall: near (< 7 m),
// far, and weak (the wall's albedo 0.3 makes echoes beyond ~70 deg incidence weaker than the 0.1 threshold).
TEST(Vlp16Physics, RangeNoiseFollowsRangeIncidenceAndPower) {
  const auto es = testing::MakeEmbree(OneWall(0.3));
  Vlp16CasterConfig config;
  config.range_noise_sigma_m = 0.01;
  config.range_noise_per_m = 0.002;
  config.range_noise_incidence_exponent = 1.0;
  config.range_noise_min_cos = 0.2;
  config.range_noise_weak_power = 0.1;
  config.range_noise_weak_max_gain = 2.0;
  config.min_intensity_for_return = 0.5;
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  Fire(*es, config, 3, &seqs, &truth);
  double sum2[3] = {0, 0, 0}, raw2[3] = {0, 0, 0};
  int n[3] = {0, 0, 0};
  for (std::size_t r = 0; r < truth.size(); ++r) {
    const LidarTruthPoint& t = truth[r];
    if (!t.returned) continue;
    const double cos_i = t.dir_world.x();
    const double power = 0.3 * cos_i * std::exp(-0.004 * t.true_range_m);
    double sigma = std::hypot(0.01, 0.002 * t.true_range_m) / std::max(cos_i, 0.2);
    if (power < 0.1) sigma *= std::min(2.0, std::sqrt(0.1 / power));
    const double e = Reported(seqs, r) - t.echo_range_m[0];
    const int part = power < 0.1 ? 2 : t.true_range_m < 7.0 ? 0 : 1;
    sum2[part] += (e / sigma) * (e / sigma);
    raw2[part] += e * e;
    ++n[part];
  }
  for (int part = 0; part < 3; ++part) {
    ASSERT_GT(n[part], 1000) << "part " << part;
    // Sampling error of a standard deviation: 1 / sqrt(2 n) <= 2.2 % here; the 2 mm code adds 0.2 %. 7 % = 3 SE.
    EXPECT_NEAR(std::sqrt(sum2[part] / n[part]), 1.0, 0.07) << "part " << part;
    std::cout << "part " << part << ": " << n[part] << " points, raw sigma " << 1e3 * std::sqrt(raw2[part] / n[part])
              << " mm, normalised " << std::sqrt(sum2[part] / n[part]) << "\n";
  }
  // The model matters: the far/oblique and weak parts are much noisier than the near head-on one.
  EXPECT_GT(std::sqrt(raw2[1] / n[1]), 1.5 * std::sqrt(raw2[0] / n[0]));
}

// Range walk: noise-free, each reported range is the true one plus the curve's bias at the echo's byte.
TEST(Vlp16Physics, RangeBiasFollowsTheCurveOfReflectivity) {
  const auto es = testing::MakeEmbree(OneWall(0.8));
  Vlp16CasterConfig config = NoiseFree();
  config.range_bias_curve = {{30.0, 0.05}, {60.0, -0.02}};
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  Fire(*es, config, 3, &seqs, &truth);
  int checked = 0, low = 0, high = 0;
  for (std::size_t r = 0; r < truth.size(); ++r) {
    if (!truth[r].returned) continue;
    const int byte = seqs[r / 16].reflectivity[r % 16];
    const double bias = byte <= 30 ? 0.05 : byte >= 60 ? -0.02 : 0.05 - 0.07 * (byte - 30) / 30.0;
    EXPECT_NEAR(Reported(seqs, r) - truth[r].echo_range_m[0], bias, 0.0011) << "byte " << byte;  // 2 mm code
    ++checked;
    low += byte <= 30, high += byte >= 60;
  }
  EXPECT_GT(checked, 10000);
  EXPECT_GT(low, 100);   // both ends of the curve are exercised (oblique parts of the wall are weak)
  EXPECT_GT(high, 100);
}

/// A mirror (x = 3, 2 m wide) facing the head, and a wall behind the head at x = -4.
Scene MirrorRoom() {
  Scene scene;
  scene.name = "mirror_room";
  scene.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, 1, 3));
  Material mirror{"mirror", 0.02, false, ""};
  mirror.specular = 0.95;
  scene.materials = {Material{"wall", 0.8, false, ""}, mirror};
  scene.primitives = {WallAt("mirror", 3.0, 0.0, 2.0, 3.0, 1), WallAt("back_wall", -4.0, 0.0, 40.0, 8.0, 0)};
  return scene;
}

// A ray that meets the mirror at x = 3 goes back to the wall at x = -4: path 3 / dx + 7 / dx. The head reports
// that folded path along its own ray (a ghost point at x = 10, behind the mirror); without specular reflections
// it reports the mirror itself.
TEST(Vlp16Physics, MirrorGivesAGhostAtTheFoldedPathLength) {
  const auto es = testing::MakeEmbree(MirrorRoom());
  for (bool specular : {false, true}) {
    Vlp16CasterConfig config = NoiseFree();
    config.specular_reflections = specular;
    std::vector<Vlp16FiringSequence> seqs;
    std::vector<LidarTruthPoint> truth;
    Fire(*es, config, 3, &seqs, &truth);
    int on_mirror = 0;
    for (std::size_t r = 0; r < truth.size(); ++r) {
      const LidarTruthPoint& t = truth[r];
      if (!t.hit || std::abs(t.p_world.x() - 3.0) > 1e-4) continue;
      ++on_mirror;
      const double dx = t.dir_world.x();
      EXPECT_NEAR(Reported(seqs, r), specular ? 10.0 / dx : 3.0 / dx, 0.0011);
    }
    EXPECT_GT(on_mirror, 500);
  }
}

/// A retroreflective plate (x = 3, y in [0, 2], z in [0, 3]) in front of a wall at x = 8.
Scene RetroBeforeWall() {
  Scene scene;
  scene.name = "retro_before_wall";
  scene.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, 1, 3));
  scene.materials = {Material{"wall", 0.8, false, ""}, Material{"retro", 0.9, true, ""}};
  scene.primitives = {WallAt("wall", 8.0, 0.0, 40.0, 8.0, 0), WallAt("retro", 3.0, 1.0, 2.0, 3.0, 1)};
  return scene;
}

// Firings whose central ray passes the plate's vertical edges within 0.9 halo (where a halo ray is sure to meet
// the plate: 8 rays on the rim leave at most 1 - cos 22.5 deg = 8 % of a straight edge uncovered) report the
// plate's range; beyond 1.05 halo (no halo ray reaches it) they report the wall. Without blooming none does.
TEST(Vlp16Physics, BloomReturnsTheRetroreflectorsRangeWithinTheHaloOnly) {
  const auto es = testing::MakeEmbree(RetroBeforeWall());
  const double halo_rad = 0.010;
  for (bool bloom : {false, true}) {
    Vlp16CasterConfig config = NoiseFree();
    config.bloom_halo_mrad = bloom ? 1e3 * halo_rad : 0.0;
    std::vector<Vlp16FiringSequence> seqs;
    std::vector<LidarTruthPoint> truth;
    Fire(*es, config, 3, &seqs, &truth);
    int inside = 0, outside = 0;
    for (std::size_t r = 0; r < truth.size(); ++r) {
      const LidarTruthPoint& t = truth[r];
      if (!t.hit || std::abs(t.p_world.x() - 8.0) > 1e-4) continue;  // central ray on the wall
      const double s = (3.0 - t.origin_world.x()) / t.dir_world.x();
      const Eigen::Vector3d at3 = t.origin_world + s * t.dir_world;
      if (at3.z() < 0.3 || at3.z() > 2.7) continue;  // beside the plate, away from its top and bottom edges
      const Eigen::Vector3d edge(3.0, at3.y() < 0.0 ? 0.0 : 2.0, at3.z());
      const Eigen::Vector3d to_edge = edge - t.origin_world;
      const double angle = std::acos(std::min(1.0, t.dir_world.dot(to_edge.normalized())));
      if (angle < 0.9 * halo_rad) {
        ++inside;
        EXPECT_NEAR(Reported(seqs, r), bloom ? to_edge.norm() : t.true_range_m, bloom ? 0.05 : 0.0011)
            << "angle " << angle;
      } else if (angle > 1.05 * halo_rad) {
        ++outside;
        EXPECT_NEAR(Reported(seqs, r), t.true_range_m, 0.0011) << "angle " << angle;
      }
    }
    // Two edges x 14 lasers in the band x 2 revolutions x ~5 azimuth steps (0.2 deg = 3.5 mrad) within 9 mrad.
    EXPECT_GT(inside, 100);
    EXPECT_GT(outside, 10000);
  }
}

// Same seed, same bytes, with every effect on; another seed changes the noise.
TEST(Vlp16Physics, SameSeedSameBytesWithEveryEffect) {
  Scene scene = RetroBeforeWall();
  Material mirror{"mirror", 0.02, false, ""};
  mirror.specular = 0.9;
  scene.materials.push_back(mirror);
  scene.primitives.push_back(WallAt("mirror", 6.0, -3.0, 2.0, 3.0, 2));
  const auto es = testing::MakeEmbree(scene);
  Vlp16CasterConfig config;
  ApplyLidarRealism(Realism::kTypical, &config);
  std::vector<Vlp16FiringSequence> a, b, c;
  Fire(*es, config, 5, &a, nullptr);
  Fire(*es, config, 5, &b, nullptr);
  Fire(*es, config, 6, &c, nullptr);
  ASSERT_EQ(a.size(), b.size());
  int differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].distance_2mm, b[i].distance_2mm);
    EXPECT_EQ(a[i].reflectivity, b[i].reflectivity);
    differ += a[i].distance_2mm != c[i].distance_2mm;
  }
  // Only the sequences that see the walls (about half the azimuths: nothing stands behind the head) can differ.
  EXPECT_GT(differ, static_cast<int>(a.size()) / 3);
}

TEST(Vlp16Physics, PresetsIdealIsTheDefaultAndHarshIsNoisier) {
  Vlp16CasterConfig ideal, typical, harsh;
  ideal.range_noise_sigma_m = 0.5;  // a preset sets the physics fields whatever they were
  ApplyLidarRealism(Realism::kIdeal, &ideal);
  const Vlp16CasterConfig defaults;
  EXPECT_EQ(ideal.range_noise_sigma_m, defaults.range_noise_sigma_m);
  EXPECT_EQ(ideal.beam_rings, defaults.beam_rings);
  EXPECT_EQ(ideal.bloom_halo_mrad, 0.0);
  EXPECT_FALSE(ideal.specular_reflections);
  ApplyLidarRealism(Realism::kTypical, &typical);
  ApplyLidarRealism(Realism::kHarsh, &harsh);
  std::string why;
  EXPECT_TRUE(typical.Validate(&why)) << why;
  EXPECT_TRUE(harsh.Validate(&why)) << why;
  EXPECT_TRUE(typical.specular_reflections);
  EXPECT_GT(typical.bloom_halo_mrad, 0.0);
  EXPECT_FALSE(typical.range_bias_curve.empty());
  EXPECT_GT(harsh.range_noise_sigma_m, typical.range_noise_sigma_m);
  EXPECT_GT(harsh.bloom_halo_mrad, typical.bloom_halo_mrad);
  EXPECT_GT(harsh.range_noise_incidence_exponent, typical.range_noise_incidence_exponent);  // the full fit
  EXPECT_GT(std::abs(harsh.range_bias_curve.front()[1]), std::abs(typical.range_bias_curve.front()[1]));
}

// The new switches are keys of the sim config's `lidar:` section, and the resolved config writes them back.
TEST(Vlp16Physics, ConfigKeysParseAndRoundTrip) {
  const YAML::Node root = YAML::Load(
      "lidar: {range_noise_per_m: 0.001, range_noise_incidence_exponent: 2.5, range_noise_min_cos: 0.2,\n"
      "        range_noise_weak_power: 0.1, range_noise_weak_max_gain: 2, range_bias_curve: [[0, 0.03], [255, -0.04]],\n"
      "        bloom_halo_mrad: 4, bloom_power_fraction: 0.1, specular_reflections: true}\n");
  SimConfig config = DefaultSimConfig();
  const Status parsed = ParseSimConfig("test.yaml", root, &config);
  ASSERT_TRUE(parsed.ok) << parsed.message;
  EXPECT_EQ(config.lidar.range_noise_incidence_exponent, 2.5);
  ASSERT_EQ(config.lidar.range_bias_curve.size(), 2u);
  EXPECT_EQ(config.lidar.range_bias_curve[1][1], -0.04);
  EXPECT_TRUE(config.lidar.specular_reflections);
  YAML::Emitter out;
  EmitSimConfig(out, config);
  SimConfig again = DefaultSimConfig();
  const Status reparsed = ParseSimConfig("resolved.yaml", YAML::Load(out.c_str()), &again);
  ASSERT_TRUE(reparsed.ok) << reparsed.message;
  EXPECT_EQ(again.lidar.range_bias_curve, config.lidar.range_bias_curve);
  EXPECT_EQ(again.lidar.bloom_halo_mrad, 4.0);
  // A decreasing curve is refused, naming the key.
  SimConfig bad = DefaultSimConfig();
  const Status refused =
      ParseSimConfig("bad.yaml", YAML::Load("lidar: {range_bias_curve: [[50, 0.01], [10, 0.0]]}"), &bad);
  EXPECT_FALSE(refused.ok);
  EXPECT_NE(refused.message.find("range_bias_curve"), std::string::npos) << refused.message;
}

}  // namespace
}  // namespace rotolidar::sim
