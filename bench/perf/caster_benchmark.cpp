// Caster throughput: one simulated VLP-16 second (18,084 sequences = 289,344 firings, 600 rpm) against
// scenes/box_room.yaml on one core. `x_realtime` = simulated seconds per CPU second (Google Benchmark's rate
// counters divide by CPU time). `rotolidar bench lidar` measures the same with the sim's own rig motion.
#include <cmath>

#include <benchmark/benchmark.h>

#include "core/util/rng.hpp"
#include "sim/lidar/vlp16_caster.hpp"
#include "sim/sim_config.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

constexpr int kSequencesPerSecond = 18084;  // 1 / 55.296 us

const EmbreeScene& BoxRoom() {
  static const std::unique_ptr<EmbreeScene> es = [] {
    Scene scene;
    Status s = LoadScene(ResolveScenePath("box_room"), &scene);
    ROTOLIDAR_CHECK(s.ok, s.message);
    std::unique_ptr<EmbreeScene> embree;
    s = EmbreeScene::Create(scene, &embree);
    ROTOLIDAR_CHECK(s.ok, s.message);
    return embree;
  }();
  return *es;
}

Pose3 Moving(Seconds t) {
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(0.2 * t, 0.1, 1.4);
  T.linear() = Eigen::AngleAxisd(0.5 * t, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

/// Arg 0: without truth (what `rotolidar sim` runs); 1: with per-firing truth; 2: 19 sub-rays (beam_rings 2);
/// 3: dual return with 7 sub-rays and glass transmission.
void BM_CasterOneSecond(benchmark::State& state) {
  const EmbreeScene& es = BoxRoom();
  Vlp16CasterConfig config;
  if (state.range(0) == 2) config.beam_rings = 2;
  if (state.range(0) == 3) {
    config.beam_rings = 1;
    config.return_mode = Vlp16ReturnMode::kDual;
    config.material_transmittance = {{"window_glass", 0.9}};
  }
  Vlp16Caster caster(es, LidarIntrinsics{}, config, 1);
  std::vector<Vlp16FiringSequence> seqs;
  std::vector<LidarTruthPoint> truth;
  for (auto _ : state) {
    seqs.clear();
    truth.clear();
    caster.Fire(kSequencesPerSecond, Moving, &seqs, state.range(0) == 1 ? &truth : nullptr);
    benchmark::DoNotOptimize(seqs.data());
  }
  state.counters["rays_per_s"] = benchmark::Counter(16.0 * caster.rays_per_firing() * kSequencesPerSecond *
                                                        state.iterations(), benchmark::Counter::kIsRate);
  state.counters["x_realtime"] = benchmark::Counter(state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_CasterOneSecond)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);

/// One second of rays from a fixed origin: in VLP-16 order (arg 1, coherent fans) or random directions (arg 0).
std::vector<RayQuery> RayBatch(bool vlp16_order) {
  RandomStream rng(1, "bench.rays");
  const LidarIntrinsics intr;
  std::vector<RayQuery> q;
  for (int k = 0; k < kSequencesPerSecond; ++k) {
    for (int i = 0; i < 16; ++i) {
      Eigen::Vector3d d;
      if (vlp16_order) {
        d = Vlp16RayDirection(intr.elevation_deg[i] * M_PI / 180.0, k * 2.0 * M_PI / 1808.4);
      } else {
        // Separate declarations: the draws happen in this order with every compiler (function arguments have none).
        const double x = rng.Normal(), y = rng.Normal(), z = rng.Normal();
        d = Eigen::Vector3d(x, y, z).normalized();
      }
      q.push_back({Eigen::Vector3d(0.0, 0.1, 1.4), d, 100.0});
    }
  }
  return q;
}

void BM_IntersectSingle(benchmark::State& state) {
  const EmbreeScene& es = BoxRoom();
  const std::vector<RayQuery> q = RayBatch(state.range(0) != 0);
  for (auto _ : state) {
    for (const RayQuery& r : q) benchmark::DoNotOptimize(es.Intersect(r.origin_world, r.dir_world, r.t_max_m));
  }
  state.counters["rays_per_s"] = benchmark::Counter(q.size() * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_IntersectSingle)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_IntersectBatch(benchmark::State& state) {
  const EmbreeScene& es = BoxRoom();
  const std::vector<RayQuery> q = RayBatch(state.range(0) != 0);
  std::vector<RayHit> hits(q.size());
  for (auto _ : state) {
    es.IntersectBatch(q.data(), q.size(), hits.data());
    benchmark::DoNotOptimize(hits.data());
  }
  state.counters["rays_per_s"] = benchmark::Counter(q.size() * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_IntersectBatch)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rotolidar::sim

BENCHMARK_MAIN();
