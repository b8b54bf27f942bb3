// The loop closer's worker: keyframe database, two-stage search, pose graph (loop_closer.hpp).
#include "core/graph/loop_closer.hpp"
#include "core/graph/loop_closer_internal.hpp"
#include "core/graph/loop_gate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/pipeline/voxel_map.hpp"
#include "core/util/log.hpp"

namespace rotolidar::graph {

namespace {

// One point per voxel (the first one in input order: deterministic), within max_range_m of the base origin.
template <class Out>
std::vector<Out> Thin(const std::vector<Eigen::Vector3f>& points, double voxel_m, double max_range_m) {
  std::vector<Eigen::Vector3d> near;
  near.reserve(points.size());
  for (const Eigen::Vector3f& p : points)
    if (p.allFinite() && p.norm() <= max_range_m) near.push_back(p.cast<double>());
  VoxelMap grid(voxel_m, 1);
  grid.Add(near);
  std::vector<Out> out;
  for (const Eigen::Vector3d& p : grid.Points()) out.push_back(p.cast<typename Out::Scalar>());
  return out;
}

// Rotation taking the world frame to a frame whose -z is gravity (yaw kept as the world's).
Eigen::Matrix3d LevelRotation(const Eigen::Vector3d& gravity_world) {
  if (!(gravity_world.norm() > 1e-9) || !gravity_world.allFinite()) return Eigen::Matrix3d::Identity();
  const Eigen::Vector3d down = gravity_world.normalized();
  return Eigen::Quaterniond::FromTwoVectors(down, -Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

Matrix6d OdometryInformation(const Pose3& T_prev_cur, const LoopClosureConfig& c) {
  const double dist_m = T_prev_cur.translation().norm();
  const double angle_rad = Eigen::AngleAxisd(T_prev_cur.linear()).angle();
  const double sigma_t = c.odometry_sigma_m + c.odometry_sigma_per_m * dist_m;
  const double sigma_r = c.odometry_sigma_rad + c.odometry_sigma_per_rad * angle_rad;
  Vector6d diag;
  diag << Eigen::Vector3d::Constant(1.0 / (sigma_t * sigma_t)), Eigen::Vector3d::Constant(1.0 / (sigma_r * sigma_r));
  return diag.asDiagonal();
}

}  // namespace

bool LoopClosureConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = "loop_closure." + m;
    return false;
  };
  if (!(keyframe_spacing_m >= 0.0) || !(keyframe_spacing_rad >= 0.0)) return fail("keyframe_spacing_*: must be >= 0");
  if (!(cloud_voxel_m > 0.0)) return fail("cloud_voxel_m: must be > 0");
  if (!(map_voxel_m >= 0.0)) return fail("map_voxel_m: must be >= 0");
  if (!(max_range_m > 0.0)) return fail("max_range_m: must be > 0");
  if (!(exclude_recent_s >= 0.0) || !(min_travel_m >= 0.0)) return fail("exclude_recent_s / min_travel_m: must be >= 0");
  if (num_candidates < 1) return fail("num_candidates: must be >= 1");
  if (!(max_descriptor_distance > 0.0 && max_descriptor_distance <= 1.0))
    return fail("max_descriptor_distance: must be in (0, 1]");
  if (!(descriptor_window_s >= 0.0 && std::isfinite(descriptor_window_s)))
    return fail("descriptor_window_s: must be >= 0 and finite");
  if (submap_neighbours < 0) return fail("submap_neighbours: must be >= 0");
  if (!(after_loop_travel_m >= 0.0)) return fail("after_loop_travel_m: must be >= 0");
  if (!(max_revisit_distance_m > 0.0)) return fail("max_revisit_distance_m: must be > 0");
  if (!(max_loop_distance_m > 0.0)) return fail("max_loop_distance_m: must be > 0");
  if (!(max_guess_offset_m > 0.0) || !(max_guess_offset_per_m >= 0.0) || !(max_guess_offset_rad > 0.0))
    return fail("max_guess_offset_*: must be > 0 (per_m >= 0)");
  if (!(odometry_sigma_m > 0.0) || !(odometry_sigma_rad > 0.0) || !(odometry_sigma_per_m >= 0.0) ||
      !(odometry_sigma_per_rad >= 0.0))
    return fail("odometry_sigma_*: floors must be > 0, shares >= 0");
  if (max_keyframes < 1) return fail("max_keyframes: must be >= 1");
  if (!(max_camera_offset_s >= 0.0)) return fail("max_camera_offset_s: must be >= 0");
  std::string why;
  if (!descriptor.Validate(&why)) return fail("descriptor: " + why);
  if (!orb.Validate(&why)) return fail("orb: " + why);
  if (!bow.Validate(&why)) return fail("bow: " + why);
  if (!verification.Validate(&why)) return fail("verification: " + why);
  if (!loop_information_floor.Validate(&why)) return fail("loop_information_floor: " + why);
  if (!graph.Validate(&why)) return fail("graph: " + why);
  return true;
}

LoopCloser::LoopCloser(const LoopClosureConfig& config) : config_(config), graph_(config.graph) {
  std::string why;
  ROTOLIDAR_CHECK(config_.Validate(&why), why);
  if (config_.threaded) worker_ = std::thread([this] { WorkerLoop(); });
}

LoopCloser::~LoopCloser() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    queue_.clear();
  }
  queue_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

Status LoopCloser::LoadVocabulary(const std::string& path) {
  auto vocabulary = std::make_unique<loop::Vocabulary>();
  if (Status s = vocabulary->Load(path); !s) return s;
  if (vocabulary->empty()) return Status::Error(path + ": the vocabulary has no words");
  vocabulary_ = std::move(vocabulary);
  return Status::Ok();
}

void LoopCloser::AddKeyframe(KeyframeInput keyframe) {
  ++offered_;
  if (has_last_offered_) {
    const Pose3 d = last_taken_T_world_base_.inverse() * keyframe.T_world_base;
    if (d.translation().norm() < config_.keyframe_spacing_m &&
        Eigen::AngleAxisd(d.linear()).angle() < config_.keyframe_spacing_rad)
      return;
  }
  has_last_offered_ = true;
  last_taken_T_world_base_ = keyframe.T_world_base;
  if (!config_.threaded) {
    Process(std::move(keyframe));
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(keyframe));
  }
  queue_cv_.notify_one();
}

void LoopCloser::Finish() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_cv_.wait(lock, [this] { return queue_.empty() && !busy_; });
}

void LoopCloser::WorkerLoop() {
  for (;;) {
    KeyframeInput next;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      queue_cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      next = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
    }
    Process(std::move(next));
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
    }
    idle_cv_.notify_all();
  }
}

void LoopCloser::Process(KeyframeInput input) {
  // A full database, or a pose the graph cannot take (non-finite odometry): the keyframe is counted, not kept.
  // Odometry rotations carry round-off (KITTI's calibration is printed to 6 digits, and composing with it leaves
  // R^T R - I ~1e-6); they are projected onto SO(3) so that the graph's 1e-6 orthonormality check holds.
  bool usable = keyframes_.size() < config_.max_keyframes && input.T_world_base.matrix().allFinite();
  if (usable) {
    const Eigen::Matrix3d R = input.T_world_base.linear();
    usable = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-3 && R.determinant() > 0.0;
    if (usable) input.T_world_base.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  }
  const int id = int(keyframes_.size());
  if (!usable || !StoreKeyframe(std::move(input), id)) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++state_.keyframes_dropped;
    return;
  }
  SearchLoops(id);
}

// The keyframe into the database, the place index and the graph (odometry edge from the previous keyframe).
// False, with state_.last_message, when the graph refuses its node; nothing is kept then.
bool LoopCloser::StoreKeyframe(KeyframeInput input, int id) {
  auto kf = std::make_unique<Keyframe>();
  kf->t_s = input.t_s;
  kf->T_world_odom = input.T_world_base;
  kf->cloud_base = Thin<Eigen::Vector3d>(input.points_base, config_.cloud_voxel_m, config_.max_range_m);
  if (config_.map_voxel_m > 0.0)
    kf->map_base = Thin<Eigen::Vector3f>(input.points_base, config_.map_voxel_m, config_.max_range_m);
  // Descriptor in the levelled frame at the base origin: yaw is the only free rotation (the index's shift search).
  kf->R_level_base = LevelRotation(input.gravity_world) * input.T_world_base.linear();
  described_ = DescribedPoints(
      id, kf->cloud_base, input.T_world_base, config_.descriptor_window_s, input.t_s,
      [&](int k) { return keyframes_[k]->t_s; }, [&](int k) { return keyframes_[k]->T_world_odom; },
      [&](int k) -> const std::vector<Eigen::Vector3d>& { return keyframes_[k]->cloud_base; });
  const loop::LidarDescriptor descriptor = LevelledDescriptor(described_, kf->R_level_base, config_.descriptor);

  Pose3 T_world_guess = input.T_world_base;
  Pose3 T_prev_cur = Pose3::Identity();
  if (id > 0) {
    // Both poses are rotations to round-off (Process projected the input; the graph's come from quaternions).
    T_prev_cur = keyframes_[id - 1]->T_world_odom.inverse() * input.T_world_base;
    T_world_guess = graph_.Pose(id - 1) * T_prev_cur;  // carry the latest correction forward
  }
  Status graph_status = graph_.AddNode(id, T_world_guess, /*fixed=*/id == 0);
  if (!graph_status) {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.last_message = graph_status.message;
    return false;
  }
  if (id > 0) {
    path_length_m_.push_back(path_length_m_.back() + T_prev_cur.translation().norm());
    PoseGraphEdge edge;
    edge.from_id = id - 1, edge.to_id = id, edge.T_from_to = T_prev_cur, edge.kind = EdgeKind::kOdometry;
    edge.information = InformationInToFrame(OdometryInformation(T_prev_cur, config_), T_prev_cur);
    graph_status = graph_.AddEdge(edge);
  } else {
    path_length_m_.push_back(0.0);
  }
  const Status index_status = index_.Add(id, input.t_s, descriptor);
  kf->has_bow = vocabulary_ && !input.image.empty() && AddImage(input.image, id, input.t_s);
  std::lock_guard<std::mutex> lock(mutex_);
  keyframes_.push_back(std::move(kf));
  state_.keyframes.push_back({id, input.t_s, input.T_world_base, T_world_guess});
  if (!graph_status) state_.last_message = graph_status.message;
  if (!index_status) state_.last_message = index_status.message;
  return true;
}

// The keyframe's image into the bag-of-words database (ORB, then the vocabulary's words); a failure is counted and
// the keyframe's stage 1 stays the LiDAR one.
bool LoopCloser::AddImage(const cv::Mat& image, int id, Seconds t_s) {
  loop::OrbFeatures features;
  loop::BowVector bow;
  Status s = loop::ExtractOrb(image, config_.orb, &features);
  if (s) s = vocabulary_->Transform(features.descriptors, &bow);
  std::lock_guard<std::mutex> lock(mutex_);  // KeyframeClouds reads bow_ from other threads
  if (s) s = bow_.Add(id, t_s, bow);
  if (!s) {
    ++state_.visual_failures;
    state_.last_message = "keyframe " + std::to_string(id) + " image: " + s.message;
    return false;
  }
  ++state_.visual_keyframes;
  return true;
}

}  // namespace rotolidar::graph
