#include "bench/loops/loop_pr.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <unordered_map>

#include <pcl/kdtree/kdtree_flann.h>

#include "bench/eval/trajectory_lookup.hpp"
#include "core/graph/loop_gate.hpp"
#include "core/io/trajectory_io.hpp"
#include "core/loop/bow_database.hpp"

namespace rotolidar::bench {

bool LoopPrConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(revisit_max_distance_m > 0.0)) return fail("revisit_max_distance_m: must be > 0");
  if (!(revisit_min_overlap > 0.0 && revisit_min_overlap <= 1.0)) return fail("revisit_min_overlap: must be in (0, 1]");
  if (!(overlap_radius_m > 0.0)) return fail("overlap_radius_m: must be > 0");
  if (!(max_loop_error_m > 0.0) || !(max_loop_error_rad > 0.0)) return fail("max_loop_error_*: must be > 0");
  return loop.Validate(error);
}

// ---------------------------------------------------------------------------------------------------------------
// Truth labels.

struct RevisitTruth::Impl {
  LoopPrConfig config;
  std::vector<Pose3> T_truth_base;                               // truth pose per keyframe
  std::vector<pcl::PointCloud<pcl::PointXYZ>::Ptr> world;        // its points at the truth pose
  // The submap around each keyframe (it and submap_neighbours either side, truth poses), built on first use.
  mutable std::vector<std::unique_ptr<pcl::KdTreeFLANN<pcl::PointXYZ>>> submap;
  mutable std::unordered_map<long long, double> overlap;         // memo: query * n + match

  const pcl::KdTreeFLANN<pcl::PointXYZ>& Submap(int id) const {
    if (!submap[id]) {
      auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
      const int k = config.loop.submap_neighbours, n = int(world.size());
      for (int j = std::max(0, id - k); j <= std::min(n - 1, id + k); ++j) *cloud += *world[j];
      submap[id] = std::make_unique<pcl::KdTreeFLANN<pcl::PointXYZ>>();
      if (!cloud->empty()) submap[id]->setInputCloud(cloud);
    }
    return *submap[id];
  }
};

RevisitTruth::RevisitTruth(const std::vector<graph::KeyframeCloud>& keyframes, const std::vector<Pose3>& T_truth_base,
                           const LoopPrConfig& config)
    : impl_(new Impl) {
  impl_->config = config;
  impl_->submap.resize(keyframes.size());
  for (size_t i = 0; i < keyframes.size(); ++i) {
    impl_->T_truth_base.push_back(T_truth_base[i]);
    auto cloud = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    for (const Eigen::Vector3d& p : keyframes[i].cloud_base) {
      const Eigen::Vector3f w = (T_truth_base[i] * p).cast<float>();
      cloud->push_back(pcl::PointXYZ(w.x(), w.y(), w.z()));
    }
    impl_->world.push_back(cloud);
  }
}

RevisitTruth::~RevisitTruth() { delete impl_; }

double RevisitTruth::Overlap(int query_id, int match_id) const {
  const long long key = (long long)query_id * (long long)impl_->world.size() + match_id;
  if (auto it = impl_->overlap.find(key); it != impl_->overlap.end()) return it->second;
  const auto& query = *impl_->world[query_id];
  const pcl::KdTreeFLANN<pcl::PointXYZ>& tree = impl_->Submap(match_id);
  double share = 0.0;
  if (!query.empty() && tree.getInputCloud()) {
    std::vector<int> index(1);
    std::vector<float> d2(1);
    const float r2 = float(impl_->config.overlap_radius_m * impl_->config.overlap_radius_m);
    size_t seen = 0;
    for (const pcl::PointXYZ& p : query)
      if (tree.nearestKSearch(p, 1, index, d2) == 1 && d2[0] <= r2) ++seen;
    share = double(seen) / double(query.size());
  }
  impl_->overlap[key] = share;
  return share;
}

double RevisitTruth::Distance(int query_id, int match_id) const {
  return (impl_->T_truth_base[query_id].translation() - impl_->T_truth_base[match_id].translation()).norm();
}

Pose3 RevisitTruth::Relative(int query_id, int match_id) const {
  return impl_->T_truth_base[match_id].inverse() * impl_->T_truth_base[query_id];
}

LoopTruthCheck CheckLoop(const RevisitTruth& truth, const graph::LoopRecord& loop, const LoopPrConfig& config) {
  LoopTruthCheck c;
  c.truth_distance_m = truth.Distance(loop.query_id, loop.match_id);
  c.truth_overlap = truth.Overlap(loop.query_id, loop.match_id);
  const Pose3 error = truth.Relative(loop.query_id, loop.match_id).inverse() * loop.T_match_query;
  c.error_m = error.translation().norm();
  c.error_rad = Eigen::AngleAxisd(error.linear()).angle();
  c.correct = c.error_m <= config.max_loop_error_m && c.error_rad <= config.max_loop_error_rad;
  return c;
}

bool RevisitTruth::IsRevisit(int query_id, int match_id) const {
  if (Distance(query_id, match_id) > impl_->config.revisit_max_distance_m) return false;
  return Overlap(query_id, match_id) >= impl_->config.revisit_min_overlap;
}

// ---------------------------------------------------------------------------------------------------------------
// The detectors.

namespace {

struct Context {
  const std::vector<graph::KeyframeCloud>& keyframes;
  const LoopPrConfig& config;
  loop::LoopVerificationConfig open_gate;  // every gate but fitness (fitness <= fine_correspondence_m anyway)
  const graph::LoopClosureConfig& loop;
  std::vector<double> path_m;              // odometry path length at each keyframe
  double verify_time_s = 0.0;
};

bool Eligible(const Context& c, int query, int match) {
  return match < query && c.keyframes[match].t_s <= c.keyframes[query].t_s - c.loop.exclude_recent_s &&
         c.path_m[query] - c.path_m[match] >= c.loop.min_travel_m;
}

// The match's submap (it and submap_neighbours either side, odometry poses), in the match's base frame.
std::vector<Eigen::Vector3d> Submap(const Context& c, int match) {
  return graph::SubmapAround(
      match, c.loop.submap_neighbours, int(c.keyframes.size()), [&](int k) { return c.keyframes[k].T_world_odom; },
      [&](int k) -> const std::vector<Eigen::Vector3d>& { return c.keyframes[k].cloud_base; });
}

// The loop closer's stage 2 on the odometry poses, with the fitness gate open (the sweep applies it).
loop::LoopVerification Verify(Context* c, int query, int match, double yaw_rad, bool* passed) {
  const auto t0 = std::chrono::steady_clock::now();
  const graph::KeyframeCloud& q = c->keyframes[query];
  const graph::KeyframeCloud& m = c->keyframes[match];
  const graph::RevisitCheck check = graph::CheckRevisit(
      q.cloud_base, q.R_level_base, [&] { return Submap(*c, match); }, m.R_level_base,
      m.T_world_odom.inverse() * q.T_world_odom, yaw_rad, c->path_m[query] - c->path_m[match], c->loop, c->open_gate);
  c->verify_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  *passed = check.outcome == graph::CandidateRecord::Outcome::kAccepted;
  return check.verification;
}

// Stage 1's proposal: the place index's best eligible keyframe (ring-key retrieval, Scan Context re-ranking).
bool Stage1(const Context& c, const loop::LidarPlaceIndex& index, const loop::LidarDescriptor& d, int query,
            loop::PlaceCandidate* best) {
  loop::PlaceQuery q;
  q.t_s = c.keyframes[query].t_s;
  q.exclude_recent_s = c.loop.exclude_recent_s;
  q.num_results = 10;  // the first one that is also far enough back on the path
  q.max_distance = 1.0;
  for (const loop::PlaceCandidate& candidate : index.Query(d, q))
    if (Eligible(c, query, int(candidate.keyframe_id))) {
      *best = candidate;
      return true;
    }
  return false;
}

// Stage 2's own proposal: the eligible keyframe nearest on the odometry poses.
int NearestOnOdometry(const Context& c, int query, const std::vector<int>& eligible) {
  int best = -1;
  double best_d = 1e300;
  for (int m : eligible) {
    const double d = (c.keyframes[m].T_world_odom.translation() - c.keyframes[query].T_world_odom.translation()).norm();
    if (d < best_d) best_d = d, best = m;
  }
  return best;
}

/// Fills p's precision (1 with no detection) and recall (0 without positives) from its tp and fp.
void SetPrecisionRecall(int positives, PrPoint* p) {
  p->precision = p->tp + p->fp > 0 ? double(p->tp) / double(p->tp + p->fp) : 1.0;
  p->recall = positives > 0 ? double(p->tp) / double(positives) : 0.0;
}

}  // namespace

std::vector<PrPoint> SweepPr(std::vector<std::pair<double, bool>> detections, int positives, bool higher_is_better) {
  std::sort(detections.begin(), detections.end(), [higher_is_better](const auto& a, const auto& b) {
    return higher_is_better ? a.first > b.first : a.first < b.first;
  });
  std::vector<PrPoint> curve;
  PrPoint p;
  for (size_t i = 0; i < detections.size(); ++i) {
    (detections[i].second ? p.tp : p.fp) += 1;
    if (i + 1 < detections.size() && detections[i + 1].first == detections[i].first) continue;
    p.threshold = detections[i].first;
    SetPrecisionRecall(positives, &p);
    curve.push_back(p);
  }
  return curve;
}

double RecallAtPrecision1(const std::vector<PrPoint>& curve) {
  double best = 0.0;
  for (const PrPoint& p : curve)
    if (p.fp == 0) best = std::max(best, p.recall);
  return best;
}

namespace {

// The visual stage 1 alone on one query: the eligible keyframe with the best eta in `bow` (the keyframes before
// the query that have a vector, as the loop closer's database). eta is the raw score over one common divisor, so
// the best eta is the best raw score; the thresholds are opened to rank every candidate.
void VisualStage1(const Context& c, const RevisitTruth& truth, const loop::BowDatabase& bow, int query,
                  LoopQueryOutcome* o) {
  const graph::KeyframeCloud& q = c.keyframes[query];
  if (q.bow.empty()) return;
  loop::LoopQueryConfig open = c.loop.bow;
  open.exclude_recent_s = c.loop.exclude_recent_s;
  open.min_normalised_score = 0.0, open.min_raw_score = 0.0;
  open.max_results = std::max(1, int(bow.size()));
  for (const loop::BowCandidate& candidate : bow.DetectLoop(q.bow, q.t_s, open).accepted) {
    const int match = int(candidate.id);
    if (!Eligible(c, query, match)) continue;
    o->visual_match = match;
    o->visual_eta = candidate.normalised_score;
    o->visual_raw_score = candidate.score;
    o->visual_true = truth.IsRevisit(query, match);
    o->visual_truth_distance_m = truth.Distance(query, match);
    o->visual_truth_overlap = truth.Overlap(query, match);
    return;
  }
}

// One query through the three detectors; `described` are the points of its descriptor d (graph::DescribedPoints).
LoopQueryOutcome RunQuery(Context* c, const RevisitTruth& truth, const loop::LidarPlaceIndex& index,
                          const std::vector<Eigen::Vector3d>& described, const loop::LidarDescriptor& d, int query,
                          const std::vector<int>& eligible) {
  LoopQueryOutcome o;
  o.query_id = query;
  o.t_query_s = c->keyframes[query].t_s;
  for (int m : eligible)
    if (truth.IsRevisit(query, m)) {
      o.positive = true;
      break;
    }
  loop::PlaceCandidate s1;
  if (Stage1(*c, index, d, query, &s1)) {
    o.stage1_match = int(s1.keyframe_id);
    o.stage1_distance = s1.match.distance;
    o.stage1_true = truth.IsRevisit(query, o.stage1_match);
    o.stage1_truth_distance_m = truth.Distance(query, o.stage1_match);
    o.stage1_truth_overlap = truth.Overlap(query, o.stage1_match);
    o.both_match = o.stage1_match;
    if (o.stage1_distance <= c->loop.max_descriptor_distance)
      o.both_fitness_m = Verify(c, query, o.stage1_match, s1.match.yaw_rad, &o.both_verified).fitness_rmse_m;
  }
  const int neighbour = NearestOnOdometry(*c, query, eligible);
  const double neighbour_m =
      (c->keyframes[neighbour].T_world_odom.translation() - c->keyframes[query].T_world_odom.translation()).norm();
  if (!o.both_verified && neighbour != o.stage1_match && neighbour_m <= c->loop.max_revisit_distance_m) {
    const graph::KeyframeCloud& nk = c->keyframes[neighbour];
    const loop::DescriptorMatch m =
        graph::DescriptorAtGuess(described, d, *index.Find(neighbour), nk.R_level_base,
                                 nk.T_world_odom.inverse() * c->keyframes[query].T_world_odom,
                                 graph::DescriptorSearchRadius(c->path_m[query] - c->path_m[neighbour], c->loop),
                                 c->loop.descriptor);
    if (m.distance <= c->loop.max_descriptor_distance) {
      bool verified = false;
      const double fitness_m = Verify(c, query, neighbour, m.yaw_rad, &verified).fitness_rmse_m;
      if (verified) o.both_match = neighbour, o.both_verified = true, o.both_fitness_m = fitness_m;
    }
  }
  if (o.both_match >= 0) o.both_true = truth.IsRevisit(query, o.both_match);
  // Stage 2's own proposal has no descriptor: its yaw guess is the odometry's (0 on top of the relative pose).
  o.stage2_match = neighbour;
  const graph::KeyframeCloud& q = c->keyframes[query];
  const graph::KeyframeCloud& m = c->keyframes[o.stage2_match];
  const Eigen::Matrix3d R = m.R_level_base * (m.T_world_odom.inverse() * q.T_world_odom).linear() *
                            q.R_level_base.transpose();  // the levelled frames' relative rotation
  const double yaw_rad = std::atan2(R(1, 0), R(0, 0));
  o.stage2_fitness_m = Verify(c, query, o.stage2_match, yaw_rad, &o.stage2_verified).fitness_rmse_m;
  o.stage2_true = truth.IsRevisit(query, o.stage2_match);
  o.stage2_truth_distance_m = truth.Distance(query, o.stage2_match);
  o.stage2_truth_overlap = truth.Overlap(query, o.stage2_match);
  return o;
}

// The visual curve and its operating point (the loop closer's acceptance: eta and the raw-score floor).
void SweepVisual(const LoopPrConfig& config, LoopPrResult* r) {
  if (r->visual_keyframes == 0) {
    r->visual_absent = "no keyframe has a bag-of-words vector (a recording without camera.csv, or no "
                       "loop_closure.vocabulary in the config)";
    return;
  }
  std::vector<std::pair<double, bool>> detections;
  PrPoint& op = r->visual_operating;
  op = PrPoint{};
  op.threshold = config.loop.bow.min_normalised_score;
  for (const LoopQueryOutcome& o : r->queries) {
    if (o.visual_match < 0) continue;
    detections.push_back({o.visual_eta, o.visual_true});
    if (o.visual_eta >= op.threshold && o.visual_raw_score >= config.loop.bow.min_raw_score)
      (o.visual_true ? op.tp : op.fp) += 1;
  }
  SetPrecisionRecall(r->positives, &op);
  r->visual = SweepPr(detections, r->positives, /*higher_is_better=*/true);
}

void Sweep(const LoopPrConfig& config, LoopPrResult* r) {
  SweepVisual(config, r);
  std::vector<std::pair<double, bool>> s1, s2, both;
  const double gate_m = config.loop.verification.max_fitness_rmse_m;
  r->operating = PrPoint{};
  r->operating.threshold = gate_m;
  for (const LoopQueryOutcome& o : r->queries) {
    if (o.stage1_match >= 0) s1.push_back({o.stage1_distance, o.stage1_true});
    if (o.stage2_verified) s2.push_back({o.stage2_fitness_m, o.stage2_true});
    if (o.both_verified) {
      both.push_back({o.both_fitness_m, o.both_true});
      if (o.both_fitness_m <= gate_m) (o.both_true ? r->operating.tp : r->operating.fp) += 1;
    }
  }
  SetPrecisionRecall(r->positives, &r->operating);
  r->stage1 = SweepPr(s1, r->positives);
  r->stage2 = SweepPr(s2, r->positives);
  r->both = SweepPr(both, r->positives);
}

}  // namespace

Status EvaluateLoopPr(const std::vector<graph::KeyframeCloud>& keyframes, const std::vector<Pose3>& T_truth_base,
                      const LoopPrConfig& config, LoopPrResult* result,
                      const std::function<void(double)>& progress) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error("loop precision/recall config: " + why);
  if (keyframes.size() != T_truth_base.size())
    return Status::Error("loop precision/recall: " + std::to_string(keyframes.size()) + " keyframes but " +
                         std::to_string(T_truth_base.size()) + " truth poses");
  *result = LoopPrResult{};
  Context c{keyframes, config, config.loop.verification, config.loop, {}, 0.0};
  c.open_gate.max_fitness_rmse_m = c.open_gate.fine_correspondence_m;
  c.path_m.assign(keyframes.size(), 0.0);
  for (size_t i = 1; i < keyframes.size(); ++i)
    c.path_m[i] = c.path_m[i - 1] +
                  (keyframes[i].T_world_odom.translation() - keyframes[i - 1].T_world_odom.translation()).norm();
  const RevisitTruth truth(keyframes, T_truth_base, config);
  loop::LidarPlaceIndexConfig index_config;
  index_config.max_keyframes = std::max<size_t>(1, keyframes.size());
  loop::LidarPlaceIndex index(index_config);
  loop::BowDatabase bow;  // the keyframes with a vector so far
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const int query = int(i);
    const std::vector<Eigen::Vector3d> described = graph::DescribedPoints(
        query, keyframes[i].cloud_base, keyframes[i].T_world_odom, config.loop.descriptor_window_s, keyframes[i].t_s,
        [&](int k) { return keyframes[k].t_s; }, [&](int k) { return keyframes[k].T_world_odom; },
        [&](int k) -> const std::vector<Eigen::Vector3d>& { return keyframes[k].cloud_base; });
    const loop::LidarDescriptor d = graph::LevelledDescriptor(described, keyframes[i].R_level_base, config.loop.descriptor);
    std::vector<int> eligible;
    for (int m = 0; m < query; ++m)
      if (Eligible(c, query, m)) eligible.push_back(m);
    if (!eligible.empty()) {
      result->queries.push_back(RunQuery(&c, truth, index, described, d, query, eligible));
      VisualStage1(c, truth, bow, query, &result->queries.back());
      if (result->queries.back().positive) ++result->positives;
    }
    if (Status s = index.Add(query, keyframes[i].t_s, d); !s)
      return Status::Error("keyframe " + std::to_string(i) + ": " + s.message);
    if (!keyframes[i].bow.empty()) {
      if (Status s = bow.Add(query, keyframes[i].t_s, keyframes[i].bow); !s)
        return Status::Error("keyframe " + std::to_string(i) + ": " + s.message);
      ++result->visual_keyframes;
    }
    if (progress && (i + 1) % std::max<size_t>(1, keyframes.size() / 10) == 0)
      progress(double(i + 1) / double(keyframes.size()));
  }
  Sweep(config, result);
  result->verify_time_s = c.verify_time_s;
  return Status::Ok();
}

Status TruthAtKeyframes(const std::string& recording, const std::vector<graph::KeyframeCloud>& keyframes,
                        std::vector<Pose3>* T_truth_base) {
  Trajectory truth;
  const std::string path = recording + "/truth/base.tum";
  if (Status s = ReadTrajectory(path, TrajectoryFormat::kTum, &truth); !s)
    return Status::Error(s.message + " (bench loops needs the twin's truth)");
  T_truth_base->clear();
  for (const graph::KeyframeCloud& k : keyframes) {
    Pose3 T;
    if (!PoseAt(truth, k.t_s, &T))
      return Status::Error(path + ": no truth at keyframe " + std::to_string(k.id) + " (t " + std::to_string(k.t_s) +
                           " s)");
    T_truth_base->push_back(T);
  }
  return Status::Ok();
}

}  // namespace rotolidar::bench
