// Loop correction time: one pose-graph solve (PoseGraph::Optimize, as the loop closer runs it on each accepted
// loop) over a run of L metres with a keyframe per metre (loop_closure.keyframe_spacing_m), closed by one loop
// from the last keyframe onto the first. The path is a square of side L / 4 driven once; the odometry overstates
// each step by 1 % and turns 0.01 deg per metre too far in yaw, plus white noise (1 cm, 0.11 deg per step), so the
// loop edge starts metres off and the whole trajectory bends. Arg: L [m].
// Counters: keyframes, LM iterations, solves (Huber warm start + Cauchy + re-solves), and the residual of the end
// against the truth before and after [m]. Wall time per solve is Google Benchmark's (one thread, like the
// loop closer's worker).
#include <algorithm>
#include <cmath>

#include <benchmark/benchmark.h>

#include "core/graph/pose_graph.hpp"
#include "core/util/rng.hpp"

namespace rotolidar::graph {
namespace {

struct Run {
  std::vector<Pose3> truth, odometry;
};

Run MakeRun(int length_m) {
  Run run;
  const int side = length_m / 4;
  RandomStream rng(1, "pose-graph-benchmark");
  for (int i = 0; i <= 4 * side; ++i) {
    const int leg = std::min(i / side, 3), s = i - leg * side;
    const double yaw = leg * M_PI / 2.0;
    const Eigen::Vector2d corner[4] = {{0, 0}, {double(side), 0}, {double(side), double(side)}, {0, double(side)}};
    const Eigen::Vector2d p = corner[leg] + double(s) * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
    Pose3 T = RotZ(yaw);
    T.translation() << p.x(), p.y(), 0.0;
    run.truth.push_back(T);
  }
  run.odometry.push_back(run.truth.front());
  for (size_t i = 1; i < run.truth.size(); ++i) {
    Pose3 step = run.truth[i - 1].inverse() * run.truth[i];
    step.translation() *= 1.01;
    // Separate declarations: the draws happen in this order with every compiler (function arguments have none).
    const double dx = rng.Normal(0, 0.01), dy = rng.Normal(0, 0.01), dz = rng.Normal(0, 0.01);
    step.translation() += Eigen::Vector3d(dx, dy, dz);
    step.linear() = step.linear() * RotZ(0.01 * M_PI / 180.0 + rng.Normal(0, 0.002)).linear();
    run.odometry.push_back(run.odometry.back() * step);
  }
  return run;
}

PoseGraph MakeGraph(const Run& run) {
  Vector6d d;
  d << Eigen::Vector3d::Constant(1.0 / (0.02 * 0.02)), Eigen::Vector3d::Constant(1.0 / (0.004 * 0.004));
  PoseGraph graph;
  for (size_t i = 0; i < run.odometry.size(); ++i) {
    (void)graph.AddNode(int(i), run.odometry[i], i == 0);
    if (i == 0) continue;
    PoseGraphEdge e;
    e.from_id = int(i) - 1, e.to_id = int(i);
    e.T_from_to = run.odometry[i - 1].inverse() * run.odometry[i];
    e.information = d.asDiagonal();
    (void)graph.AddEdge(e);
  }
  PoseGraphEdge loop;  // the last keyframe onto the first, as GICP measures it (the truth)
  loop.from_id = 0, loop.to_id = int(run.truth.size()) - 1, loop.kind = EdgeKind::kLoop;
  loop.T_from_to = run.truth.front().inverse() * run.truth.back();
  loop.information = (Vector6d() << 1e4, 1e4, 1e4, 1e5, 1e5, 1e5).finished().asDiagonal();
  (void)graph.AddEdge(loop);
  return graph;
}

void BM_LoopCorrection(benchmark::State& state) {
  const Run run = MakeRun(int(state.range(0)));
  const PoseGraph graph = MakeGraph(run);
  PoseGraphResult result;
  PoseGraph solved;
  for (auto _ : state) {
    solved = graph;  // the loop closer solves a copy of its graph
    result = solved.Optimize();
    benchmark::DoNotOptimize(result.final_cost);
  }
  const int last = int(run.truth.size()) - 1;
  state.counters["keyframes"] = double(run.truth.size());
  state.counters["iterations"] = result.iterations;
  state.counters["solves"] = result.num_solves;
  state.counters["converged"] = result.converged ? 1.0 : 0.0;
  state.counters["end_error_before_m"] = (run.odometry.back().translation() - run.truth.back().translation()).norm();
  state.counters["end_error_after_m"] = (solved.Pose(last).translation() - run.truth.back().translation()).norm();
}
BENCHMARK(BM_LoopCorrection)->Arg(1000)->Arg(2000)->Arg(4000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace rotolidar::graph

BENCHMARK_MAIN();
