#include "bench/run/keyframe_db.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/io/csv.hpp"
#include "core/io/point_cloud_io.hpp"

namespace rotolidar::bench {
namespace {

const std::vector<std::string> kColumns = {
    "t_s",   "id",    "odom_x_m", "odom_y_m", "odom_z_m", "odom_qx", "odom_qy", "odom_qz", "odom_qw",
    "corr_x_m", "corr_y_m", "corr_z_m", "corr_qx", "corr_qy", "corr_qz", "corr_qw",
    "level_qx", "level_qy", "level_qz", "level_qw", "num_points"};

std::string PointFile(const std::string& dir, int id) {
  char name[32];
  std::snprintf(name, sizeof(name), "kf_%06d.pcd", id);
  return dir + "/" + name;
}

void AppendPose(const Pose3& T, std::vector<double>* row) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d t = T.translation();
  row->insert(row->end(), {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()});
}

// A quaternion from 4 CSV values (x y z w); false when it is not of unit length (1e-6).
bool ReadRotation(const double* v, Eigen::Matrix3d* R) {
  const Eigen::Quaterniond q(v[3], v[0], v[1], v[2]);
  if (!(std::abs(q.norm() - 1.0) < 1e-6)) return false;
  *R = q.normalized().toRotationMatrix();
  return true;
}

bool ReadPose(const double* v, Pose3* T) {
  *T = Pose3::Identity();
  T->translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  Eigen::Matrix3d R;
  if (!ReadRotation(v + 3, &R)) return false;
  T->linear() = R;
  return true;
}

}  // namespace

Status WriteKeyframeDatabase(const std::string& dir, const std::vector<graph::KeyframeCloud>& keyframes) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Status::Error(dir + ": cannot create folder: " + ec.message());
  CsvWriter csv;
  if (Status s = csv.Open(dir + "/keyframes.csv", kColumns); !s) return s;
  for (const graph::KeyframeCloud& k : keyframes) {
    std::vector<double> row = {k.t_s, double(k.id)};
    AppendPose(k.T_world_odom, &row);
    AppendPose(k.T_world_corrected, &row);
    const Eigen::Quaterniond q(k.R_level_base);
    row.insert(row.end(), {q.x(), q.y(), q.z(), q.w(), double(k.cloud_base.size())});
    csv.Row(row);
    // An empty keyframe (nothing within range) has no point file (num_points 0).
    if (!k.cloud_base.empty())
      if (Status s = SavePointCloud(PointFile(dir, k.id), k.cloud_base); !s) return s;
  }
  return csv.Close();
}

Status ReadKeyframeDatabase(const std::string& dir, std::vector<graph::KeyframeCloud>* keyframes) {
  keyframes->clear();
  const std::string path = dir + "/keyframes.csv";
  CsvReader csv;
  if (Status s = csv.Open(path, kColumns); !s) return s;
  std::vector<double> v;
  while (csv.Next(&v)) {
    const std::string where = path + ":" + std::to_string(csv.line());
    graph::KeyframeCloud k;
    k.t_s = v[0];
    k.id = int(v[1]);
    if (!(v[1] == double(keyframes->size())))
      return Status::Error(where + ": id: expected " + std::to_string(keyframes->size()) + " (ids count up from 0)");
    if (!ReadPose(&v[2], &k.T_world_odom)) return Status::Error(where + ": odom_q*: not a unit quaternion");
    if (!ReadPose(&v[9], &k.T_world_corrected)) return Status::Error(where + ": corr_q*: not a unit quaternion");
    if (!ReadRotation(&v[16], &k.R_level_base)) return Status::Error(where + ": level_q*: not a unit quaternion");
    if (!(v[20] >= 0.0) || v[20] != std::floor(v[20])) return Status::Error(where + ": num_points: not a count");
    const size_t num_points = size_t(v[20]);
    if (num_points > 0) {
      if (Status s = LoadPointCloud(PointFile(dir, k.id), &k.cloud_base); !s) return Status::Error(where + ": " + s.message);
      if (k.cloud_base.size() != num_points)
        return Status::Error(where + ": num_points: " + std::to_string(num_points) + " but " + PointFile(dir, k.id) +
                             " holds " + std::to_string(k.cloud_base.size()));
    }
    keyframes->push_back(std::move(k));
  }
  return csv.status();
}

}  // namespace rotolidar::bench
