// The estimator's state side: motion prediction, scan-to-map registration, LiDAR-IMU fusion in the sliding window
// (with IMU initialisation) and the maps. docs/estimator.md.
#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "core/backend/pose_factors.hpp"
#include "core/io/recording.hpp"
#include "core/pipeline/estimator_internal.hpp"
#include "core/util/log.hpp"

namespace rotolidar {
namespace {

Pose3 PoseOf(const NavState& s) {
  Pose3 T = Pose3::Identity();
  T.linear() = s.R_world_imu;
  T.translation() = s.p_world_m;
  return T;
}

/// Relative motion a -> b scaled to a fraction s of itself (constant twist; rotation and translation apart).
Pose3 ScaleMotion(const Pose3& delta, double s) {
  Pose3 out = Pose3::Identity();
  out.linear() = ExpSO3(s * LogSO3(delta.linear()));
  out.translation() = s * delta.translation();
  return out;
}

/// The held pose as a measurement: 1 mm and 0.5 mrad (1 sigma), far tighter than a registration, since a still
/// rig's pose is known exactly; only the window's IMU noise moves it.
Matrix6d StaticHoldInformation() {
  constexpr double kSigmaM = 0.001, kSigmaRad = 0.0005;
  Vector6d d;
  d << Eigen::Vector3d::Constant(1.0 / (kSigmaM * kSigmaM)), Eigen::Vector3d::Constant(1.0 / (kSigmaRad * kSigmaRad));
  return d.asDiagonal();
}

DegeneracyRecord MakeDegeneracyRecord(const DegeneracyInfo& info) {
  DegeneracyRecord rec;
  rec.degenerate = info.degenerate;
  rec.eigenvalues = info.eigenvalues;
  rec.num_degenerate = int(info.degenerate_directions.size());
  rec.directions = info.degenerate_directions;
  for (const Vector6d& d : info.degenerate_directions) rec.axis_weight = rec.axis_weight.cwiseMax(d.cwiseAbs());
  return rec;
}

/// The most the offset removed from the IMU stamps moves per scan [s]: half the 1 ms sample spacing of a 1 kHz
/// IMU, so that stamps shifted before and after a step stay in order (a 200 Hz IMU's are 5 ms apart).
constexpr double kMaxImuOffsetStepS = 0.5e-3;

/// The gyro reading at t_s (the latest sample at or before it; the first when none is) [rad/s]; imu not empty.
Eigen::Vector3d GyroAt(const std::vector<ImuSample>& imu, Seconds t_s) {
  auto after = std::upper_bound(imu.begin(), imu.end(), t_s, [](Seconds t, const ImuSample& s) { return t < s.t_s; });
  return after == imu.begin() ? imu.front().gyro_radps : std::prev(after)->gyro_radps;
}

}  // namespace

std::optional<PreintegratedImu> PreintegrateSpan(const std::vector<ImuSample>& imu, Seconds t0_s, Seconds t1_s,
                                                 const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                                                 const ImuNoise& noise) {
  if (imu.empty() || !(t1_s > t0_s)) return std::nullopt;
  PreintegratedImu pre(bg, ba, noise);
  Seconds t = t0_s;
  auto step = [&](const ImuSample& a, const ImuSample& b, Seconds until) {
    const double dt = std::min(until, t1_s) - t;
    if (dt <= 0) return;
    if (pre.Integrate(0.5 * (a.gyro_radps + b.gyro_radps), 0.5 * (a.accel_mps2 + b.accel_mps2), dt)) t += dt;
  };
  if (imu.front().t_s > t) step(imu.front(), imu.front(), imu.front().t_s);
  for (size_t i = 0; i + 1 < imu.size() && t < t1_s; ++i)
    if (imu[i + 1].t_s > t) step(imu[i], imu[i + 1], imu[i + 1].t_s);
  if (t < t1_s) step(imu.back(), imu.back(), t1_s);
  if (pre.num_steps() == 0) return std::nullopt;
  return pre;
}

Estimator::Prediction Estimator::Predict(Seconds t0_s, Seconds t1_s) const {
  if (imu_initialized() && !imu_.empty()) return PredictFromWindow(t0_s, t1_s);
  return PredictConstantVelocity(t0_s, t1_s);
}

// The window's latest state propagated by the IMU to the scan start; the scan's motion integrated from there
// with the predicted velocity, gravity and the window's biases.
Estimator::Prediction Estimator::PredictFromWindow(Seconds t0_s, Seconds t1_s) const {
  Prediction out;
  const NavState latest = window_->latest_state();
  NavState state = latest;
  if (t0_s > window_->latest_time_s()) {
    out.imu_since_latest = PreintegrateSpan(imu_, window_->latest_time_s(), t0_s, latest.bias_gyro_radps,
                                            latest.bias_accel_mps2, calib_.imu);
    if (out.imu_since_latest) state = window_->PredictFromLatest(*out.imu_since_latest);
  }
  out.T_world_base = PoseOf(state) * calib_.T_base_imu.inverse();
  ImuMotionModel model;
  model.v_imu_mps = state.R_world_imu.transpose() * state.v_world_mps;
  model.gravity_imu_mps2 = state.R_world_imu.transpose() * window_->gravity_world_mps2();
  model.bias_gyro_radps = state.bias_gyro_radps;
  model.bias_accel_mps2 = state.bias_accel_mps2;
  out.imu_motion = bool(ImuMotionTable(imu_, t0_s, t1_s, model, calib_.T_base_imu, &out.motion));
  if (!out.imu_motion) out.motion = IdentityTable(t0_s, t1_s);
  return out;
}

// The pose the registration measured best: the scan's middle, T_world_base(t0) * table(t_mid); with no deskew
// applied (ProcessDeskewedScan), the scan start itself.
void Estimator::RecordMeasuredPose(Seconds t0_s, Seconds t1_s, const MotionTable* applied) {
  const Pose3& T_world_start = trajectory_.back().T_ref_body;
  const Seconds t_mid = applied ? 0.5 * (t0_s + t1_s) : t0_s;
  measured_poses_.push_back({t_mid, applied ? T_world_start * MotionTablePose(*applied, t_mid) : T_world_start});
  // The last two give the twist; without the IMU those of the velocity window stay too (PredictConstantVelocity).
  constexpr Seconds kStampSlackS = 0.01;  // mid-scan stamps are not exactly periodic
  const Seconds keep_s = config_.use_imu ? 0.0 : config_.lidar_only_velocity_window_s;
  while (measured_poses_.size() > 2 && measured_poses_.front().t_s < t_mid - keep_s - kStampSlackS)
    measured_poses_.pop_front();
}

// Before the IMU is initialised (or without one): constant velocity from the last two measured poses (without the
// IMU, the translation velocity over lidar_only_velocity_window_s); where IMU samples cover the span, the rotation
// comes from the gyro (accelerometer unused: gravity is not known yet).
Estimator::Prediction Estimator::PredictConstantVelocity(Seconds t0_s, Seconds t1_s) const {
  Prediction out;
  out.motion = IdentityTable(t0_s, t1_s);
  // Motion over one second in the last pose's frame (constant twist); none before two poses (the first scans:
  // zero velocity, yet the gyro below still removes the carrier's rotation during the scan).
  // The twist comes from the measured poses (mid-scan, RecordMeasuredPose): a deskew with a wrong velocity shifts
  // the scan-start pose but hardly its middle, so the velocity error does not feed back (KISS-ICP's reason to
  // deskew about the scan's middle; Vizzo et al., RA-L 2023).
  Pose3 delta_per_s = Pose3::Identity();
  if (!measured_poses_.empty()) {
    const StampedPose& b = measured_poses_.back();
    if (measured_poses_.size() >= 2) {
      const StampedPose& a = measured_poses_[measured_poses_.size() - 2];
      if (b.t_s > a.t_s) delta_per_s = ScaleMotion(a.T_ref_body.inverse() * b.T_ref_body, 1.0 / (b.t_s - a.t_s));
      // Without the IMU (RecordMeasuredPose kept the velocity window): the translation velocity is the mean over
      // the window, the rotation stays the last two scans'. A rotary scan that sees only sky and ground errs by
      // centimetres along its weak axis; the last two poses turn that into a velocity error that the next guess
      // extrapolates, while a turn's onset needs the latest rotation rate.
      const StampedPose& f = measured_poses_.front();
      if (measured_poses_.size() >= 3 && b.t_s > f.t_s)
        delta_per_s.translation() = b.T_ref_body.linear().transpose() *
                                    (b.T_ref_body.translation() - f.T_ref_body.translation()) / (b.t_s - f.t_s);
    }
    out.T_world_base = b.T_ref_body * ScaleMotion(delta_per_s, t0_s - b.t_s);
    if (t1_s > t0_s) out.motion = ConstantTwistTable(ScaleMotion(delta_per_s, t1_s - t0_s), t0_s, t1_s);
  }
  if (imu_.empty()) return out;
  // Velocity of the imu origin in the imu frame, from the base's constant twist.
  const Pose3& T_bi = calib_.T_base_imu;
  const Pose3 delta_imu = T_bi.inverse() * ScaleMotion(delta_per_s, 1e-3) * T_bi;  // 1 ms of motion
  ImuMotionModel model;
  model.use_accel = false;
  model.v_imu_mps = delta_imu.translation() / 1e-3;
  MotionTable to_start;
  if (!trajectory_.empty() && t0_s > trajectory_.back().t_s &&
      ImuMotionTable(imu_, trajectory_.back().t_s, t0_s, model, T_bi, &to_start))
    out.T_world_base = trajectory_.back().T_ref_body * to_start.T_start_t.back();
  MotionTable scan;
  if (ImuMotionTable(imu_, t0_s, t1_s, model, T_bi, &scan)) out.motion = std::move(scan);
  return out;
}

// Feature scan-to-map against the local map (degeneracy-aware); the first scan defines the map.
Pose3 Estimator::Register(const FeatureSet& features, const Pose3& T_world_base_guess, ScanReport* report,
                          Matrix6d* information_base) {
  const Stopwatch watch;
  information_base->setZero();
  RegistrationSummary& s = report->registration;
  if (local_map_.empty()) {
    s.message = "first scan: defines the map";
    report->timings.register_ms = watch.ms();
    return T_world_base_guess;
  }
  if (HoldStaticStart(report)) {
    s.message = "static start: IMU still, pose held";
    // Once the window runs, the hold is a measurement (a zero-velocity update): the rig has not moved.
    if (imu_initialized()) *information_base = StaticHoldInformation();
    report->timings.register_ms = watch.ms();
    return trajectory_.back().T_ref_body;
  }
  s.attempted = true;
  const ScanToMapResult r = rotolidar::Register(features, local_map_, T_world_base_guess, config_.registration);
  s.converged = r.converged;
  s.remapped = r.remapped;
  s.iterations = r.iterations;
  s.solver_iterations = r.solver_iterations;
  s.neighbour_searches = r.neighbour_searches;
  s.edge_inliers = r.edge_inliers;
  s.planar_inliers = r.planar_inliers;
  s.initial_cost = r.initial_cost;
  s.final_cost = r.final_cost;
  s.rmse_m = r.rmse_m;
  s.message = r.message;
  s.hessian_eigenvalues = Eigen::SelfAdjointEigenSolver<Matrix6d>(r.hessian, Eigen::EigenvaluesOnly).eigenvalues();
  report->degeneracy = MakeDegeneracyRecord(r.degeneracy);
  // Usable: converged, or ran out of rebuilds with enough matches (then down-weighted).
  const bool enough = r.edge_inliers + r.planar_inliers >= config_.registration.min_correspondences;
  const double scale = r.converged ? 1.0 : (enough ? config_.unconverged_information_scale : 0.0);
  Pose3 T = T_world_base_guess;
  if (scale > 0 && r.T_map_scan.matrix().allFinite()) {
    *information_base =
        scale * InformationFromRegistration(r.hessian, config_.lidar_point_sigma_m, r.degeneracy.projection);
    T = r.T_map_scan;
  }
  report->timings.register_ms = watch.ms();
  return T;
}

// A rotary LiDAR standing still sees one new band of the sphere per scan: registering a band against the few
// bands before it is ill-posed (a static lab start drifted 10 cm / 3.8 deg in 1 s). While the IMU says the rig
// has not moved since the start, the pose is held and the bands build the map instead.
// The hold lasts while the IMU stays still, across IMU initialisation: the window then takes over from the held
// pose without a step (registering against the few bands of a young map pulled the pose by ~1.4 deg), and the
// map keeps growing from the held pose until the rig moves.
// A fixed sensor (motor_speed_radps 0, e.g. a KITTI car's HDL-64E) sees the whole view every scan, so nothing is
// ill-posed, and an IMU cannot tell constant velocity from rest: the KITTI 00 twin, setting off smoothly, was
// held for 36 frames while the car covered 33 m. No hold there.
bool Estimator::HoldStaticStart(ScanReport* report) {
  if (!config_.hold_static_start || !static_start_ || imu_.empty() || trajectory_.empty()) return false;
  if (calib_.motor_speed_radps == 0.0) return false;
  const Seconds t1 = report->t_end_s;
  static_start_ = ImuIsStill(imu_, t1 - config_.imu_init.static_window_s, t1, config_.imu_init, nullptr);
  report->held_static = static_start_;
  return static_start_;
}

// LiDAR-only until the IMU is initialised (the poses feed the moving initialisation); then one window state per
// scan with its IMU factor and the LiDAR factor (no information along degenerate directions).
Pose3 Estimator::Fuse(Seconds t_s, const Pose3& T_world_base_lidar, const Matrix6d& information_base,
                      const Prediction& prediction, ScanReport* report) {
  const Stopwatch watch;
  const Pose3& T_bi = calib_.T_base_imu;
  Pose3 T_world_base = T_world_base_lidar;
  if (imu_initialized() && prediction.imu_since_latest) {
    std::optional<LidarPoseMeasurement> lidar;
    if (information_base.norm() > 0) {
      lidar = LidarMeasurementInImuFrame(T_world_base_lidar, information_base, T_bi);
      lidar->rotor_offset_applied_rad = rotor_.angle_offset_rad();  // what this scan's deskew removed
      if (config_.window.estimate_time_offset) {  // what the IMU stamps lost, and the rate that moves the pose
        lidar->time_offset_applied_s = imu_time_offset_s_;
        lidar->angular_velocity_imu_radps = GyroAt(imu_, t_s) - window_->latest_state().bias_gyro_radps;
      }
    }
    if (Status st = window_->AddState(t_s, *prediction.imu_since_latest, lidar); st) {
      if (visual_) {
        const Status v =
            window_->AddVisualObservations(visual_->ObservationsAt(t_s, T_world_base_lidar, &report->visual));
        if (!v) LOG_WARN("estimator: camera observations at " << t_s << " s not used: " << v.message);
      }
      window_->Optimize();
      // The next scans' encoder angles lose the estimated offset (0 unless the window estimates it).
      rotor_.set_angle_offset_rad(window_->rotor_offset_rad());
      report->rotor_offset_rad = window_->rotor_offset_rad();
      // The IMU samples that follow lose the time offset, approached by at most kMaxImuOffsetStepS per scan: a
      // larger step would stamp a sample before the last one buffered (the estimate moved 8 ms in one scan while
      // a 20 ms offset converged). A sample fed before this step keeps the older shift, at most one step away
      // from the next measurement's time_offset_applied_s.
      imu_time_offset_s_ +=
          std::clamp(window_->time_offset_s() - imu_time_offset_s_, -kMaxImuOffsetStepS, kMaxImuOffsetStepS);
      report->imu_time_offset_s = window_->time_offset_s();
      const NavState x = window_->latest_state();
      T_world_base = PoseOf(x) * T_bi.inverse();
      report->v_world_mps = x.v_world_mps;
      report->bias_gyro_radps = x.bias_gyro_radps;
      report->bias_accel_mps2 = x.bias_accel_mps2;
    } else {
      LOG_WARN("estimator: window state at " << t_s << " s rejected: " << st.message);
    }
  } else if (!imu_initialized() && !imu_.empty()) {
    init_poses_imu_.push_back(T_world_base * T_bi);
    init_times_s_.push_back(t_s);
    TryInitializeImu();
  }
  report->imu_initialized = imu_initialized();
  report->T_world_base = T_world_base;
  trajectory_.push_back({t_s, T_world_base});
  report->timings.fuse_ms = watch.ms();
  return T_world_base;
}

// A keyframe's map-side features into the local map, less those arriving where earlier scans saw free space
// (moving objects); then the dense map.
void Estimator::UpdateMap(Seconds t_s, const FeatureSet& features, const Pose3& T_world_base, ScanReport* report) {
  const Stopwatch watch;
  const bool young = int(local_map_.num_keyframes()) < config_.initial_keyframes;
  const bool forced = config_.keyframe_every_scans > 0 && ++scans_since_keyframe_ >= config_.keyframe_every_scans;
  if (young || local_map_.NeedsKeyframe(T_world_base) || forced) {
    if (free_space_) {
      FeatureSet kept;
      kept.less_sharp = features.less_sharp;
      kept.less_flat = features.less_flat;
      report->num_dynamic_features =
          DropSeenThrough(*free_space_, t_s, T_world_base, {&kept.less_sharp, &kept.less_flat});
      local_map_.AddKeyframe(kept, T_world_base);
    } else {
      local_map_.AddKeyframe(features, T_world_base);
    }
    scans_since_keyframe_ = 0;
    report->keyframe = true;
    if (loop_closer_) HandKeyframeToLoopCloser(t_s, T_world_base);
  }
  report->map_free_space = AddToDenseMap(t_s, T_world_base, false);
  report->map_points = dense_map_.NumPoints();
  if (visual_) visual_->AddDepthPoints(t_s, T_world_base, preprocessed_);
  report->timings.map_ms = watch.ms();
}

// A copy of the keyframe's preprocessed points for the loop closer (its own thread does the rest), with the
// window's gravity (world) for its levelled descriptor; before IMU initialisation world -z.
void Estimator::HandKeyframeToLoopCloser(Seconds t_s, const Pose3& T_world_base) {
  graph::KeyframeInput keyframe;
  keyframe.t_s = t_s;
  keyframe.T_world_base = T_world_base;
  if (window_ && window_->initialized()) keyframe.gravity_world = window_->gravity_world_mps2();
  keyframe.points_base.reserve(preprocessed_.size());
  for (const ScanPoint& p : preprocessed_) keyframe.points_base.push_back(p.p_base);
  double best_offset_s = config_.loop_closure.max_camera_offset_s;
  for (const CameraFrame& f : camera_frames_)  // the frame nearest the keyframe, if near enough
    if (std::abs(f.t_s - t_s) <= best_offset_s) best_offset_s = std::abs(f.t_s - t_s), keyframe.image = f.image;
  loop_closer_->AddKeyframe(std::move(keyframe));
}

namespace {

/// Whether the loop closer's visual stage 1 keeps a frame at t_s: it has a vocabulary and the last kept frame is
/// at least max_camera_offset_s older.
bool LoopClosureWantsFrame(const graph::LoopCloser* closer, const std::deque<CameraFrame>& kept,
                           double max_camera_offset_s, Seconds t_s) {
  if (!closer || !closer->has_vocabulary()) return false;
  return kept.empty() || t_s - kept.back().t_s >= max_camera_offset_s;
}

}  // namespace

bool Estimator::WantsCameraFrame(Seconds t_s) const {
  return (visual_ && visual_->WantsFrame(t_s)) ||
         LoopClosureWantsFrame(loop_closer_.get(), camera_frames_, config_.loop_closure.max_camera_offset_s, t_s);
}

void Estimator::Feed(const CameraFrame& frame) {
  if (visual_ && !frame.image.empty()) visual_->Track(frame);
  if (frame.image.empty() || !LoopClosureWantsFrame(loop_closer_.get(), camera_frames_,
                                                    config_.loop_closure.max_camera_offset_s, frame.t_s))
    return;
  camera_frames_.push_back(frame);
  constexpr double kKeepS = 1.0;  // keyframes are handed over within a scan (~0.1-0.4 s) of their time
  while (!camera_frames_.empty() && camera_frames_.front().t_s < frame.t_s - kKeepS) camera_frames_.pop_front();
}

void Estimator::Feed(const CameraFrameRef& ref) {
  const bool loop = LoopClosureWantsFrame(loop_closer_.get(), camera_frames_,
                                          config_.loop_closure.max_camera_offset_s, ref.t_s);
  if (!loop) {
    if (visual_) visual_->Track(ref);  // decoded where it is tracked (when it wants the frame)
    return;
  }
  CameraFrame frame;
  if (Status s = LoadCameraFrame(ref, &frame); !s) {
    LOG_WARN("camera frame at " << ref.t_s << " s: " << s.message);
    return;
  }
  Feed(frame);
}

FreeSpaceCounts Estimator::FlushMap() {
  return free_space_ ? AddToDenseMap(0.0, Pose3::Identity(), true) : FreeSpaceCounts{};
}

// World points in stack chunks (no per-scan heap buffer; the map sees the same sequence as in one call). With the
// free-space test, the scan waits in the filter and the points of the scan delay_s older come out, less the
// dynamic ones (only points the map would take are tested); the new scan's image first rechecks the map's newest
// points (MapRecheck), and what enters now is tracked for that recheck.
FreeSpaceCounts Estimator::AddToDenseMap(Seconds t_s, const Pose3& T_world_base, bool flush) {
  constexpr size_t kChunk = 256;
  Eigen::Vector3d chunk[kChunk];
  size_t n = 0;
  map_kept_.clear();
  std::vector<size_t>* kept = map_recheck_ ? &map_kept_ : nullptr;
  auto accept = [&](const Eigen::Vector3d& p_world) {
    chunk[n++] = p_world;
    if (n == kChunk) {
      dense_map_.Add(chunk, n, kept);
      n = 0;
    }
  };
  FreeSpaceCounts counts;
  if (free_space_) {
    if (!flush) free_space_->AddScan(t_s, T_world_base, preprocessed_, config_.output_map_max_range_m);
    if (map_recheck_ && !flush) counts.removed = RecheckDenseMap(t_s);
    counts += free_space_->Release(flush, [&](const Eigen::Vector3d& p) { return !dense_map_.Full(p); }, accept);
  } else {
    for (const ScanPoint& p : preprocessed_)
      if (p.range_m <= config_.output_map_max_range_m) accept(T_world_base * p.p_base.cast<double>());
  }
  dense_map_.Add(chunk, n, kept);
  if (map_recheck_ && !flush) map_recheck_->Track(t_s, dense_map_, map_kept_);
  return counts;
}

// The newest scan's image judges the dense map's recent points again; those it and the scans before it saw
// through in a row leave the map.
size_t Estimator::RecheckDenseMap(Seconds t_s) {
  map_removed_.clear();
  map_recheck_->Vote(t_s, free_space_->Newest(), &map_removed_);
  size_t removed = 0;
  for (size_t index : map_removed_) removed += dense_map_.Remove(index);
  return removed;
}

void Estimator::DropOldData(Seconds t_s) {
  // Before initialisation every sample since the first LiDAR-only pose is needed (static / moving start).
  Seconds keep_from = t_s - 1.0;
  if (!imu_initialized() && !init_times_s_.empty()) keep_from = std::min(keep_from, init_times_s_.front() - 2.0);
  if (imu_initialized()) keep_from = std::min(keep_from, window_->latest_time_s() - 0.1);
  size_t n = 0;
  while (n + 2 < imu_.size() && imu_[n + 1].t_s < keep_from) ++n;
  if (n > 0) imu_.erase(imu_.begin(), imu_.begin() + long(n));
}

}  // namespace rotolidar
