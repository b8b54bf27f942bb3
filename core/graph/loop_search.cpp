// The loop closer's search (stage 1 -> stage 2 -> graph) and its outputs (loop_closer.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/graph/loop_closer.hpp"
#include "core/graph/loop_closer_internal.hpp"
#include "core/graph/loop_gate.hpp"
#include "core/pipeline/voxel_map.hpp"

namespace rotolidar::graph {

const char* ToString(CandidateRecord::Outcome outcome) {
  switch (outcome) {
    case CandidateRecord::Outcome::kDescriptorRejected: return "descriptor_rejected";
    case CandidateRecord::Outcome::kTooFar: return "too_far";
    case CandidateRecord::Outcome::kGicpFailed: return "gicp_failed";
    case CandidateRecord::Outcome::kBeyondDrift: return "beyond_drift";
    case CandidateRecord::Outcome::kGraphError: return "graph_error";
    case CandidateRecord::Outcome::kAccepted: return "accepted";
  }
  return "?";
}

const char* ToString(CandidateRecord::Source source) {
  switch (source) {
    case CandidateRecord::Source::kLidar: return "lidar";
    case CandidateRecord::Source::kVisual: return "visual";
    case CandidateRecord::Source::kGraph: return "graph";
  }
  return "?";
}

double LoopCloser::PathLengthBetween(int older_id, int newer_id) const {
  return path_length_m_[newer_id] - path_length_m_[older_id];
}

// Stage 1: the camera's bag of words when the keyframe has an image in it, else the LiDAR place index; each
// candidate goes to stage 2 until one is accepted. After an accepted loop the search pauses (after_loop_travel_m).
// When stage 1 found nothing, the keyframe nearest on the current graph is proposed as well (LIO-SAM's radius
// search): with little drift the graph itself knows the revisit, and a look-alike place elsewhere cannot hide it
// (on the parking lot's second lap the descriptor's best was the wrong place for 53 of 113 revisiting keyframes).
void LoopCloser::SearchLoops(int id) {
  if (index_.Find(id) == nullptr || path_length_m_[id] - last_loop_path_m_ < config_.after_loop_travel_m) return;
  bool found = keyframes_[id]->has_bow ? SearchVisual(id) : SearchLidar(id);
  if (!found) {
    const int neighbour = NearestOnGraph(id);
    bool tried = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (auto c = state_.candidates.rbegin(); c != state_.candidates.rend() && c->query_id == id; ++c)
        tried = tried || c->match_id == neighbour;
    }
    if (neighbour >= 0 && !tried) {
      CandidateRecord record;
      record.query_id = id, record.match_id = neighbour, record.source = CandidateRecord::Source::kGraph;
      found = TryCandidate(record, DescriptorAtGuess(described_, *index_.Find(id),
                                                     *index_.Find(neighbour), keyframes_[neighbour]->R_level_base,
                                                     graph_.Pose(neighbour).inverse() * graph_.Pose(id),
                                                     DescriptorSearchRadius(PathLengthBetween(neighbour, id), config_),
                                                     config_.descriptor));
    }
  }
  if (found) last_loop_path_m_ = path_length_m_[id];
}

// The eligible keyframe (exclude_recent_s older, min_travel_m back on the path) nearest the query on the current
// graph, within max_revisit_distance_m; -1 when none. Linear in the keyframes (a few microseconds per thousand).
int LoopCloser::NearestOnGraph(int id) const {
  const Eigen::Vector3d p = graph_.Pose(id).translation();
  int best = -1;
  double best_m = config_.max_revisit_distance_m;
  for (int m = 0; m < id && keyframes_[m]->t_s <= keyframes_[id]->t_s - config_.exclude_recent_s; ++m) {
    if (PathLengthBetween(m, id) < config_.min_travel_m) continue;
    const double d = (graph_.Pose(m).translation() - p).norm();
    if (d < best_m) best_m = d, best = m;
  }
  return best;
}

// The seed's stage 1: keyframes whose images score eta >= bow.min_normalised_score; stage 2 then needs the LiDAR
// descriptors to agree (max_descriptor_distance) before GICP.
bool LoopCloser::SearchVisual(int id) {
  loop::BowVector bow;
  bow_.Find(id, &bow);
  loop::LoopQueryConfig query = config_.bow;
  query.exclude_recent_s = config_.exclude_recent_s;
  int tried = 0;
  for (const loop::BowCandidate& c : bow_.DetectLoop(bow, keyframes_[id]->t_s, query).accepted) {
    const int match_id = int(c.id);
    if (PathLengthBetween(match_id, id) < config_.min_travel_m) continue;
    if (tried++ >= config_.num_candidates) break;
    CandidateRecord record;
    record.query_id = id, record.match_id = match_id, record.source = CandidateRecord::Source::kVisual, record.bow_score = c.normalised_score;
    const loop::DescriptorMatch match = loop::DescriptorDistance(*index_.Find(id), *index_.Find(match_id));
    if (TryCandidate(record, match)) return true;
  }
  return false;
}

// Stage 1 without a camera: the place index's best earlier keyframes by Scan Context distance.
bool LoopCloser::SearchLidar(int id) {
  loop::PlaceQuery query;
  query.t_s = keyframes_[id]->t_s;
  query.exclude_recent_s = config_.exclude_recent_s;
  query.num_results = config_.num_candidates;
  query.max_distance = config_.max_descriptor_distance;  // stage 2's descriptor gate
  for (const loop::PlaceCandidate& c : index_.Query(*index_.Find(id), query)) {
    const int match_id = int(c.keyframe_id);
    if (PathLengthBetween(match_id, id) < config_.min_travel_m) continue;
    CandidateRecord record;
    record.query_id = id, record.match_id = match_id;
    if (TryCandidate(record, c.match)) return true;
  }
  return false;
}

// One stage-1 candidate through stage 2 (the descriptor gate, then VerifyCandidate), recorded (State().candidates)
// whatever its outcome.
bool LoopCloser::TryCandidate(CandidateRecord record, const loop::DescriptorMatch& match) {
  record.descriptor_distance = match.distance;
  bool accepted = false;
  if (match.distance > config_.max_descriptor_distance)
    record.outcome = CandidateRecord::Outcome::kDescriptorRejected;
  else
    accepted = VerifyCandidate(match, &record);
  std::lock_guard<std::mutex> lock(mutex_);
  ++state_.candidates_proposed;
  if (record.outcome != CandidateRecord::Outcome::kTooFar &&
      record.outcome != CandidateRecord::Outcome::kDescriptorRejected)
    ++state_.candidates_checked;
  state_.candidates.push_back(record);
  return accepted;
}

// Stage 2 (CheckRevisit) on the graph's current poses; an accepted candidate becomes a loop edge. Fills record
// (outcome, scores); true when the loop edge went into the graph.
bool LoopCloser::VerifyCandidate(const loop::DescriptorMatch& match, CandidateRecord* record) {
  const int id = record->query_id, match_id = record->match_id;
  const Pose3 T_match_query_guess = graph_.Pose(match_id).inverse() * graph_.Pose(id);
  const auto t0 = std::chrono::steady_clock::now();
  const RevisitCheck check = CheckRevisit(
      keyframes_[id]->cloud_base, keyframes_[id]->R_level_base, [&] { return Submap(match_id); },
      keyframes_[match_id]->R_level_base, T_match_query_guess, match.yaw_rad, PathLengthBetween(match_id, id),
      config_, config_.verification);
  record->graph_distance_m = check.guess_distance_m;
  record->outcome = check.outcome;
  if (check.outcome == CandidateRecord::Outcome::kTooFar) return false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.verify_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  const loop::LoopVerification& v = check.verification;
  record->fitness_rmse_m = v.fitness_rmse_m, record->overlap = v.overlap, record->reason = v.reason;
  if (check.outcome != CandidateRecord::Outcome::kAccepted) return false;
  record->outcome = CandidateRecord::Outcome::kGraphError;
  if (!AddLoopEdge(id, match_id, v, match.distance)) return false;
  record->outcome = CandidateRecord::Outcome::kAccepted;
  return true;
}

// The verified loop into the graph (GICP's covariance as its information), then a re-solve.
bool LoopCloser::AddLoopEdge(int id, int match_id, const loop::LoopVerification& v, double descriptor_distance) {
  PoseGraphEdge edge;
  edge.from_id = match_id, edge.to_id = id, edge.T_from_to = v.T_target_source, edge.kind = EdgeKind::kLoop;
  Matrix6d information_target;
  Status s = InformationFromCovariance(v.covariance, config_.loop_information_floor, &information_target);
  if (s) {
    edge.information = InformationInToFrame(information_target, v.T_target_source);
    s = graph_.AddEdge(edge);
  }
  if (!s) {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.last_message = s.message;
    return false;
  }
  LoopRecord record;
  record.query_id = id, record.match_id = match_id;
  record.t_query_s = keyframes_[id]->t_s, record.t_match_s = keyframes_[match_id]->t_s;
  record.T_match_query = v.T_target_source;
  record.descriptor_distance = descriptor_distance;
  record.fitness_rmse_m = v.fitness_rmse_m, record.overlap = v.overlap;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.loops.push_back(record);
  }
  Solve();
  return true;
}

// Re-optimises the graph and publishes the corrected poses and the loops' verdicts.
void LoopCloser::Solve() {
  const PoseGraphResult result = graph_.Optimize();
  std::vector<bool> rejected(graph_.num_edges(), false);
  for (size_t e : result.rejected_loop_edges) rejected[e] = true;
  std::lock_guard<std::mutex> lock(mutex_);
  ++state_.graph_solves;
  state_.last_solve_time_s = result.solve_time_s;
  state_.max_solve_time_s = std::max(state_.max_solve_time_s, result.solve_time_s);
  state_.last_solve_converged = result.converged;
  if (!result.message.empty()) state_.last_message = result.message;
  for (KeyframePose& k : state_.keyframes) k.T_world_corrected = graph_.Pose(k.id);
  size_t loop_index = 0;
  for (size_t e = 0; e < graph_.num_edges(); ++e) {
    if (graph_.edges()[e].kind != EdgeKind::kLoop) continue;
    if (loop_index < state_.loops.size()) state_.loops[loop_index].rejected = rejected[e];
    ++loop_index;
  }
}

// The candidate and its neighbours' points in the candidate's frame (graph poses: the submap is consistent with
// any correction so far).
std::vector<Eigen::Vector3d> LoopCloser::Submap(int center_id) const {
  return SubmapAround(
      center_id, config_.submap_neighbours, int(keyframes_.size()), [&](int k) { return graph_.Pose(k); },
      [&](int k) -> const std::vector<Eigen::Vector3d>& { return keyframes_[k]->cloud_base; });
}

size_t LoopCloser::GraphSolves() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_.graph_solves;
}

LoopClosureState LoopCloser::State() const {
  std::lock_guard<std::mutex> lock(mutex_);
  LoopClosureState s = state_;
  s.keyframes_offered = offered_;
  return s;
}

Trajectory LoopCloser::Correct(const Trajectory& odometry) const {
  std::vector<KeyframeCorrection> corrections;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const KeyframePose& k : state_.keyframes) corrections.push_back({k.t_s, k.T_world_odom, k.T_world_corrected});
  }
  Trajectory out = odometry;
  if (corrections.empty()) return out;
  if (!CorrectTrajectory(corrections, CorrectionMode::kInterpolate, &out)) return odometry;
  return out;
}

std::vector<Eigen::Vector3d> LoopCloser::CorrectedMap(double voxel_m, int points_per_voxel) const {
  std::lock_guard<std::mutex> lock(mutex_);
  VoxelMap map(voxel_m, points_per_voxel);
  std::vector<Eigen::Vector3d> world;
  for (const KeyframePose& k : state_.keyframes) {
    world.clear();
    for (const Eigen::Vector3f& p : keyframes_[k.id]->map_base) world.push_back(k.T_world_corrected * p.cast<double>());
    map.Add(world);
  }
  return map.Points();
}

std::vector<KeyframeCloud> LoopCloser::KeyframeClouds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<KeyframeCloud> out;
  out.reserve(state_.keyframes.size());
  for (const KeyframePose& k : state_.keyframes) {
    const Keyframe& kf = *keyframes_[k.id];
    out.push_back({k.id, k.t_s, k.T_world_odom, k.T_world_corrected, kf.R_level_base, kf.cloud_base, {}});
    if (kf.has_bow) bow_.Find(k.id, &out.back().bow);  // bow_ grows under mutex_ (AddImage)
  }
  return out;
}

}  // namespace rotolidar::graph
