#include "core/pipeline/visual_frontend.hpp"

#include <chrono>
#include <functional>
#include <cmath>
#include <limits>

#include "core/util/log.hpp"
#include "core/util/validation.hpp"

namespace rotolidar {
namespace {

/// Tangents of the camera's half angles (x, y) widened by margin_rad: the view cone c.z > 0, |c.x| <= x c.z,
/// |c.y| <= y c.z of a point c in the camera frame.
Eigen::Vector2f ViewTangents(const CameraIntrinsics& camera, double margin_rad) {
  return {float(std::tan(std::atan(0.5 * camera.width_px / camera.fx_px) + margin_rad)),
          float(std::tan(std::atan(0.5 * camera.height_px / camera.fy_px) + margin_rad))};
}

bool InView(const Eigen::Vector3f& c, const Eigen::Vector2f& tangents, float min_z_m) {
  return c.z() > min_z_m && std::abs(c.x()) <= tangents.x() * c.z() && std::abs(c.y()) <= tangents.y() * c.z();
}

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

bool VisualConfig::Validate(std::string* error) const {
  if (!tracker.Validate(error) || !landmarks.Validate(error) || !depth.Validate(error)) return false;
  if (!(max_image_offset_s > 0.0) || !std::isfinite(max_image_offset_s))
    return FailValidation(error, "visual.max_image_offset_s must be > 0");
  if (!(depth_cloud_s >= 0.0) || !std::isfinite(depth_cloud_s))
    return FailValidation(error, "visual.depth_cloud_s must be >= 0");
  if (!(depth_cloud_max_range_m > 0.0)) return FailValidation(error, "visual.depth_cloud_max_range_m must be > 0");
  if (!(max_tracking_rate_hz >= 0.0) || !std::isfinite(max_tracking_rate_hz))
    return FailValidation(error, "visual.max_tracking_rate_hz must be >= 0");
  if (!(registration_weak_gate_m > 0.0) || !std::isfinite(registration_weak_gate_m))
    return FailValidation(error, "visual.registration_weak_gate_m must be > 0");
  if (!(depth_view_margin_rad >= 0.0 && depth_view_margin_rad < 1.0))
    return FailValidation(error, "visual.depth_view_margin_rad must be in [0, 1)");
  return true;
}

VisualFrontEnd::VisualFrontEnd(const VisualConfig& config, const RigCalib& calib)
    : config_(config),
      calib_(calib),
      tracker_(config.tracker),
      landmarks_(config.landmarks, CameraExtrinsic(calib), 0.5 * (calib.camera.fx_px + calib.camera.fy_px)) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  if (config.track_in_thread) {
    decoder_ = std::thread([this] { DecodeLoop(); });
    tracker_thread_ = std::thread([this] { TrackLoop(); });
  }
}

VisualFrontEnd::~VisualFrontEnd() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  decode_cv_.notify_all();
  track_cv_.notify_all();
  if (decoder_.joinable()) decoder_.join();
  if (tracker_thread_.joinable()) tracker_thread_.join();
}

bool VisualFrontEnd::WantsFrame(Seconds t_s) const {
  return !last_tracked_s_ || !(config_.max_tracking_rate_hz > 0.0) ||
         t_s - *last_tracked_s_ >= 0.9 / config_.max_tracking_rate_hz;
}

void VisualFrontEnd::Track(const CameraFrame& frame) {
  if (WantsFrame(frame.t_s)) Enqueue({frame, std::nullopt});
}

void VisualFrontEnd::Track(const CameraFrameRef& ref) {
  if (!WantsFrame(ref.t_s)) return;
  CameraFrame frame;
  frame.t_s = ref.t_s;
  Enqueue({frame, ref});
}

void VisualFrontEnd::Enqueue(Pending pending) {
  last_tracked_s_ = pending.frame.t_s;
  if (!decoder_.joinable()) return TrackNow(std::move(pending));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    in_flight_.push_back(pending.frame.t_s);
    decode_queue_.push_back(std::move(pending));
  }
  decode_cv_.notify_one();
}

// One stage of the pipeline: takes the frames of `queue` in order, runs `work` on each outside the lock and
// `done` under it.
void VisualFrontEnd::StageLoop(std::condition_variable& cv, std::deque<Pending>& queue,
                               const std::function<void(Pending&)>& work, const std::function<void(Pending&)>& done) {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv.wait(lock, [&] { return stop_ || !queue.empty(); });
    if (stop_) return;
    Pending pending = std::move(queue.front());
    queue.pop_front();
    lock.unlock();
    work(pending);
    lock.lock();
    done(pending);
  }
}

void VisualFrontEnd::DecodeLoop() {
  StageLoop(decode_cv_, decode_queue_, [](Pending& p) { Decode(&p); }, [this](Pending& p) {
    track_queue_.push_back(std::move(p));
    track_cv_.notify_one();
  });
}

void VisualFrontEnd::TrackLoop() {
  StageLoop(track_cv_, track_queue_, [this](Pending& p) { TrackNow(std::move(p)); }, [this](Pending&) {
    in_flight_.pop_front();
    idle_cv_.notify_all();
  });
}

void VisualFrontEnd::WaitForTracking(Seconds t_limit_s) {
  if (!decoder_.joinable()) return;
  std::unique_lock<std::mutex> lock(mutex_);
  idle_cv_.wait(lock, [&] { return in_flight_.empty() || in_flight_.front() > t_limit_s; });
}

void VisualFrontEnd::Decode(Pending* pending) {
  if (!pending->ref) return;
  if (Status s = LoadCameraFrame(*pending->ref, &pending->frame); !s) {
    LOG_WARN("camera frame at " << pending->frame.t_s << " s: " << s.message);
    pending->unreadable = true;
  }
  pending->ref.reset();
}

void VisualFrontEnd::TrackNow(Pending pending) {
  Decode(&pending);
  if (pending.unreadable) return;
  const CameraFrame& frame = pending.frame;
  const visual::FeatureTrackResult r = tracker_.Track(frame, calib_.camera);
  if (!r.ok) {
    LOG_WARN("camera frame at " << frame.t_s << " s not tracked: " << r.message);
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  recent_.push_back(r);
  constexpr double kKeepS = 0.3;  // states come every scan (0.1 s) and look back at most max_image_offset_s
  while (!recent_.empty() && recent_.front().t_s < frame.t_s - kKeepS) recent_.pop_front();
}

void VisualFrontEnd::AddDepthPoints(Seconds t_s, const Pose3& T_world_base, const std::vector<ScanPoint>& points) {
  if (!(config_.depth_cloud_s > 0.0)) return;
  const Eigen::Vector2f cone = ViewTangents(calib_.camera, config_.depth_view_margin_rad);
  const Eigen::Matrix4f T_cam_base = calib_.T_base_cam.inverse().matrix().cast<float>();
  const Eigen::Matrix4f T_world = T_world_base.matrix().cast<float>();
  DepthScan scan{t_s, {}};
  for (const ScanPoint& p : points) {
    if (p.range_m > config_.depth_cloud_max_range_m) continue;
    const Eigen::Vector3f c = (T_cam_base * p.p_base.homogeneous()).head<3>();
    if (!InView(c, cone, 0.0f)) continue;
    scan.points_world.push_back((T_world * p.p_base.homogeneous()).head<3>());
  }
  depth_cloud_.push_back(std::move(scan));
  while (!depth_cloud_.empty() && depth_cloud_.front().t_s < t_s - config_.depth_cloud_s) depth_cloud_.pop_front();
}

// The depth cloud's points that can be a neighbour of a fresh feature's ray (the LidarDepthMap drops those behind
// the camera), then one query per fresh feature. Only the points near some feature's ray are indexed
// (visual::RayNeighbourhood): the same depths as over the whole cloud at a fraction of the index's cost.
std::vector<double> VisualFrontEnd::LidarDepths(const std::vector<Eigen::Vector2d>& normalized,
                                                const Pose3& T_world_cam, int* valid) {
  std::vector<double> depths(normalized.size(), std::numeric_limits<double>::quiet_NaN());
  *valid = 0;
  if (normalized.empty() || depth_cloud_.empty()) return depths;
  const Eigen::Matrix4f T_cam_world = T_world_cam.inverse().matrix().cast<float>();
  const double radius_rad = config_.depth.search_radius_deg * M_PI / 180.0;
  // The view widened by twice the search radius: no point beyond can be a neighbour of a feature's ray.
  const Eigen::Vector2f cone = ViewTangents(calib_.camera, 2.0 * radius_rad);
  const visual::RayNeighbourhood neighbourhood(normalized, radius_rad);
  std::vector<Eigen::Vector3d> near;
  for (const DepthScan& scan : depth_cloud_)
    for (const Eigen::Vector3f& p : scan.points_world) {
      const Eigen::Vector3f c = (T_cam_world * p.homogeneous()).head<3>();
      if (!InView(c, cone, float(config_.depth.min_depth_m))) continue;
      if (neighbourhood.Contains(c)) near.push_back(c.cast<double>());
    }
  visual::LidarDepthMap map(config_.depth);
  if (map.Build(near) == 0) return depths;
  for (size_t i = 0; i < normalized.size(); ++i) {
    const visual::FeatureDepth d = map.Query(normalized[i]);
    if (!d.valid) continue;
    depths[i] = d.depth_m;
    ++*valid;
  }
  return depths;
}

std::vector<VisualObservation> VisualFrontEnd::ObservationsAt(Seconds t_s, const Pose3& T_world_base,
                                                             VisualScanReport* report) {
  const double td_s = landmarks_.time_offset_s();  // t_imu = t_cam + td
  // Every frame that can be chosen (t_img + td within max_image_offset_s of t_s) is tracked first; frames the
  // worker finished beyond that are ignored, so the choice does not depend on its timing.
  const Seconds t_limit_s = t_s - td_s + config_.max_image_offset_s;
  WaitForTracking(t_limit_s);
  std::vector<visual::FeatureTrackResult> frames;  // the candidates, copied out of the worker's reach
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const visual::FeatureTrackResult& r : recent_)
      if (r.t_s <= t_limit_s) frames.push_back(r);
  }
  *report = VisualScanReport{};
  for (const visual::FeatureTrackResult& r : frames)
    if (!last_state_s_ || r.t_s > *last_state_s_ - td_s + config_.max_image_offset_s)
      ++report->frames_tracked, report->track_ms += r.stats.time_ms;
  last_state_s_ = t_s;
  const VisualLandmarkStats stats = landmarks_.stats();
  report->landmarks = stats.live, report->factors = stats.factors, report->rejected_total = stats.rejected_total;
  report->sigma_px = stats.sigma_px, report->residual_median_px = stats.residual_median_px;
  report->time_offset_s = td_s;
  const visual::FeatureTrackResult* best = nullptr;
  for (const visual::FeatureTrackResult& r : frames)
    if (!best || std::abs(r.t_s + td_s - t_s) < std::abs(best->t_s + td_s - t_s)) best = &r;
  if (!best || std::abs(best->t_s + td_s - t_s) > config_.max_image_offset_s) return {};
  report->image = true;
  report->image_offset_s = best->t_s + td_s - t_s;
  report->tracked = best->stats.tracked, report->inliers = best->stats.inliers;
  report->new_features = best->stats.new_features;
  std::vector<VisualObservation> out;
  std::vector<Eigen::Vector2d> fresh;  // features that will start a landmark: they need a depth
  std::vector<size_t> fresh_index;
  for (const visual::TrackedFeature& f : best->features) {
    VisualObservation o;
    o.feature_id = f.id;
    o.normalized = f.normalized + f.velocity_normalized_ps * (t_s - best->t_s - td_s);  // to the state's time
    o.velocity_normalized_ps = f.velocity_normalized_ps;
    o.td_s = td_s;
    o.lidar_depth_m = std::numeric_limits<double>::quiet_NaN();
    if (!landmarks_.HasLandmark(f.id)) fresh.push_back(o.normalized), fresh_index.push_back(out.size());
    out.push_back(o);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<double> depths = LidarDepths(fresh, T_world_base * calib_.T_base_cam, &report->lidar_depths);
  for (size_t i = 0; i < fresh_index.size(); ++i) out[fresh_index[i]].lidar_depth_m = depths[i];
  report->depth_ms = MsSince(t0);
  report->observations = int(out.size());
  return out;
}

}  // namespace rotolidar
