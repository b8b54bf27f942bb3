#include "bench/run/loop_outputs.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "bench/run/atomic_write.hpp"
#include "core/io/csv.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/io/trajectory_io.hpp"

namespace rotolidar::bench {

// One row per accepted stage-2 loop: the two keyframes, GICP's relative pose and scores, the graph's verdict.
Status WriteLoopTable(const std::string& path, const graph::LoopClosureState& state) {
  CsvWriter csv;
  if (Status s = csv.Open(path, {"t_query_s", "t_match_s", "query_id", "match_id", "x_m", "y_m", "z_m", "qx", "qy",
                                 "qz", "qw", "descriptor_distance", "fitness_rmse_m", "overlap", "rejected"});
      !s)
    return s;
  for (const graph::LoopRecord& l : state.loops) {
    const Eigen::Quaterniond q(l.T_match_query.linear());
    const Eigen::Vector3d t = l.T_match_query.translation();
    csv.Row({l.t_query_s, l.t_match_s, double(l.query_id), double(l.match_id), t.x(), t.y(), t.z(), q.x(), q.y(),
             q.z(), q.w(), l.descriptor_distance, l.fitness_rmse_m, l.overlap, double(l.rejected)});
  }
  return csv.Close();
}

// One row per stage-1 candidate: the pair, the descriptor and graph distances, how far it got (outcome words:
// graph::ToString), GICP's scores.
Status WriteCandidateTable(const std::string& path, const graph::LoopClosureState& state) {
  std::ofstream out(path);
  out << "query_id,match_id,t_query_s,t_match_s,source,bow_score,descriptor_distance,graph_distance_m,outcome,"
         "fitness_rmse_m,overlap\n";
  for (const graph::CandidateRecord& c : state.candidates)
    out << c.query_id << ',' << c.match_id << ',' << state.keyframes[c.query_id].t_s << ','
        << state.keyframes[c.match_id].t_s << ',' << graph::ToString(c.source) << ',' << c.bow_score << ','
        << c.descriptor_distance << ',' << c.graph_distance_m << ',' << graph::ToString(c.outcome) << ','
        << c.fitness_rmse_m << ',' << c.overlap << '\n';
  return out ? Status::Ok() : Status::Error(path + ": write failed");
}

Status WriteLoopOutputs(const std::string& out_dir, const graph::LoopCloser& loops,
                        const graph::LoopClosureState& state, const Trajectory& odometry,
                        const EstimatorConfig& config) {
  if (Status s = WriteTrajectory(out_dir + "/trajectory_odometry.tum", TrajectoryFormat::kTum, odometry); !s) return s;
  if (Status s = WriteLoopTable(out_dir + "/loops.csv", state); !s) return s;
  if (Status s = WriteCandidateTable(out_dir + "/loop_candidates.csv", state); !s) return s;
  const std::vector<Eigen::Vector3d> corrected =
      loops.CorrectedMap(config.output_map_voxel_m, config.output_map_points_per_voxel);
  if (corrected.empty()) return Status::Ok();  // no map points kept (loop_closure.map_voxel_m: 0)
  return SavePointCloud(out_dir + "/map_corrected.ply", corrected);
}

Status LoopSnapshotWriter::Poll(const Estimator& estimator) {
  const graph::LoopCloser* loops = estimator.loop_closer();
  if (loops == nullptr) return Status::Ok();
  const size_t solves = loops->GraphSolves();
  if (solves == seen_solves_) return Status::Ok();
  seen_solves_ = solves;
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) return Status::Error(dir_ + ": cannot create folder: " + ec.message());
  char prefix[32];
  std::snprintf(prefix, sizeof(prefix), "/%03zu_", solves);
  const std::vector<Eigen::Vector3d> map =
      loops->CorrectedMap(estimator.config().output_map_voxel_m, estimator.config().output_map_points_per_voxel);
  const Trajectory trajectory = loops->Correct(estimator.trajectory());
  if (!map.empty())  // empty when the loop closer keeps no map points (loop_closure.map_voxel_m: 0)
    if (Status s = WriteAtomically(dir_ + prefix + "map.ply",
                                   [&](const std::string& part) { return SavePointCloud(part, map); });
        !s)
      return s;
  if (Status s = WriteAtomically(dir_ + prefix + "trajectory.tum", [&](const std::string& part) {
        return WriteTrajectory(part, TrajectoryFormat::kTum, trajectory);
      });
      !s)
    return s;
  ++written_;
  return Status::Ok();
}

}  // namespace rotolidar::bench
