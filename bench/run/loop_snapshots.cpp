#include "bench/run/loop_snapshots.hpp"

#include <cstdio>
#include <filesystem>

#include "core/io/point_cloud_io.hpp"
#include "core/io/trajectory_io.hpp"

namespace rotolidar::bench {
namespace {

// `write` into a temporary name with the same extension ("NNN_map.part.ply": writers pick the format by it), then
// rename onto path.
template <class Write>
Status WriteAtomically(const std::string& path, Write write) {
  const std::filesystem::path p(path);
  const std::string part = (p.parent_path() / (p.stem().string() + ".part" + p.extension().string())).string();
  if (Status s = write(part); !s) return s;
  std::error_code ec;
  std::filesystem::rename(part, path, ec);
  return ec ? Status::Error(path + ": cannot rename from " + part + ": " + ec.message()) : Status::Ok();
}

}  // namespace

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
