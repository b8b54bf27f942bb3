#pragma once
// What a loop-closed run writes beside its trajectory (rotolidar slam, slam --kitti; docs/loop_closure.md):
//   trajectory_odometry.tum  the odometry before loop closure (T_world_base at each scan start, TUM)
//   loops.csv                accepted loops: times, keyframe ids, GICP's T_match_query, scores, the graph's verdict
//   loop_candidates.csv      every stage-1 candidate, its source and how far it got
//   map_corrected.ply        the keyframes' points at their corrected poses [world, m]
//
// Snapshots of a loop-closed run while it runs: after each pose-graph solve (an accepted loop), the dense map and
// the trajectory so far rebuilt from the corrected keyframe poses, the seed's "ghost" removal (LV-SLAM, Sensors
// 2025, Fig. 5c/d) made visible step by step. Files, in <out_dir>/loop_snapshots/ (NNN = the solve count):
//   NNN_map.ply         CorrectedMap at the estimator's output voxel [world, m]
//   NNN_trajectory.tum  the odometry so far through LoopCloser::Correct (T_world_base at each scan start)
// Each file is written to a temporary name and renamed, so a reader never sees half of one. The loop closer
// solves in its own thread: a snapshot shows the scans processed when the solve was seen (polled after each
// scan), so its length is not deterministic; the final outputs are.
#include <string>
#include <utility>

#include "core/pipeline/estimator.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

/// Writes the four files above into out_dir (after LoopCloser::Finish; map_corrected.ply only when the loop closer
/// keeps map points, loop_closure.map_voxel_m > 0). Fails naming the file.
Status WriteLoopOutputs(const std::string& out_dir, const graph::LoopCloser& loops,
                        const graph::LoopClosureState& state, const Trajectory& odometry,
                        const EstimatorConfig& config);

class LoopSnapshotWriter {
 public:
  explicit LoopSnapshotWriter(std::string out_dir) : dir_(std::move(out_dir) + "/loop_snapshots") {}
  /// Writes a snapshot when the loop closer has solved since the last call; no-op without a loop closer. Fails
  /// naming the file that could not be written.
  Status Poll(const Estimator& estimator);
  size_t written() const { return written_; }

 private:
  std::string dir_;
  size_t seen_solves_ = 0, written_ = 0;
};

}  // namespace rotolidar::bench
