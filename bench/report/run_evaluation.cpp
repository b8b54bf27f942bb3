#include "bench/report/run_evaluation.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>

#include "bench/eval/alignment.hpp"
#include "bench/eval/statistics.hpp"
#include "bench/eval/trajectory_lookup.hpp"
#include "bench/eval/trajectory_metrics.hpp"
#include "bench/metrics/surface_distance.hpp"
#include "bench/report/html_report.hpp"
#include "bench/run/progress.hpp"
#include "bench/run/truth_eval.hpp"
#include "core/io/trajectory_io.hpp"
#include "sim/sim_config.hpp"
#include "core/util/log.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

double PathLength(const Trajectory& t) {
  double length = 0.0;
  for (size_t i = 1; i < t.size(); ++i)
    length += (t[i].T_ref_body.translation() - t[i - 1].T_ref_body.translation()).norm();
  return length;
}

/// Translation RPE over `delta_m` of travelled path (all pairs), or `frames` apart when the path is shorter.
EvalResult ComputeRpe(const Trajectory& ref, const Trajectory& est, const RunEvaluationOptions& o,
                      std::string* delta) {
  EvalResult r;
  r.unit = "m";
  r.num_associated = est.size();
  RpeOptions rpe;
  rpe.relation = PoseRelation::kTranslation;
  rpe.all_pairs = true;
  if (PathLength(ref) >= 1.5 * o.rpe_delta_m) {
    rpe.delta = o.rpe_delta_m, rpe.delta_unit = DeltaUnit::kMeters;
    *delta = Fmt("%g m", o.rpe_delta_m);
  } else {
    rpe.delta = o.rpe_fallback_frames, rpe.delta_unit = DeltaUnit::kFrames;
    *delta = std::to_string(o.rpe_fallback_frames) + " frames";
  }
  r.title = "RPE w.r.t. translation part (m) for delta = " + *delta + " (all pairs)";
  r.status = ComputeRpeErrors(ref, est, rpe, &r.errors);
  r.stats = ComputeStatistics(r.errors);
  return r;
}

/// APE, RPE and the aligned trajectories; false with `truth_note` when there is no usable truth.
Status EvaluateTrajectory(const std::string& recording_dir, const SlamRunResult& slam,
                          const RunEvaluationOptions& options, RunEvaluation* out) {
  const std::string truth_path = recording_dir + "/truth/base.tum";
  if (!fs::exists(truth_path)) {
    out->truth_note = "no ground truth (" + truth_path + " does not exist, e.g. a real-rig recording)";
    return Status::Ok();
  }
  Trajectory truth_full;
  if (Status s = ReadTrajectory(truth_path, TrajectoryFormat::kTum, &truth_full); !s) return s;
  if (Status s = EvaluateAgainstTruth(truth_full, truth_path, slam.trajectory, &out->ape); !s) return s;
  // The same association as EvaluateAgainstTruth: truth interpolated at the estimate's stamps it covers.
  out->truth = InterpolateTrajectory(truth_full, slam.trajectory);
  Trajectory est;
  for (const StampedPose& p : slam.trajectory)
    if (p.t_s >= truth_full.front().t_s && p.t_s <= truth_full.back().t_s) est.push_back(p);
  if (est.size() != out->truth.size()) return Status::Error(truth_path + ": truth/estimate association mismatch");
  out->estimate_aligned = ApplyAlignment(out->ape.alignment, est);
  out->T_scene_slam = out->T_scene_map = out->ape.alignment.T_ref_est;
  // map.ply is the odometry's dense map. With loop closure the trajectory above is the corrected one, and the
  // odometry's drift would put the map off the scene under its alignment: the map takes the odometry
  // trajectory's own (the loop-closed map is map_corrected.ply).
  if (!slam.odometry_trajectory.empty() && slam.loops.keyframes_offered > 0) {
    EvalResult odometry;
    if (Status s = EvaluateAgainstTruth(truth_full, truth_path, slam.odometry_trajectory, &odometry); !s) return s;
    out->T_scene_map = odometry.alignment.T_ref_est;
  }
  out->rpe = ComputeRpe(out->truth, est, options, &out->rpe_delta);
  out->has_truth = true;
  return Status::Ok();
}

/// The deskew error over the scans that kept their points (every slam.deskew_scan_stride-th); a note instead of
/// an error when the run kept none or the truth has no lidar.tum.
Status EvaluateDeskewError(const std::string& recording_dir, const SlamRunResult& slam, RunEvaluation* out) {
  const size_t k = slam.deskew_scan_stride;
  if (k == 0) {
    out->deskew_note = "no deskew error: the run kept no deskewed points (EstimatorConfig::keep_deskewed)";
    return Status::Ok();
  }
  if (!fs::exists(recording_dir + "/truth/lidar.tum")) {
    out->deskew_note = "no deskew error: " + recording_dir + "/truth/lidar.tum does not exist";
    return Status::Ok();
  }
  DeskewTruth truth;
  if (Status s = LoadDeskewTruth(recording_dir, &truth); !s) return s;
  DeskewErrorAccumulator acc(std::move(truth));
  for (size_t i = 0; i < slam.scans.size(); i += k)
    if (Status s = acc.Add(slam.scans[i]); !s) return s;
  out->deskew = acc.Result();
  out->deskew_scan_stride = k;
  out->has_deskew = out->deskew.all.count > 0;
  if (!out->has_deskew) out->deskew_note = "no deskew error: no deskewed point lies inside the truth's span";
  return Status::Ok();
}

/// The run's scene (`scene_name_or_path`, or when empty the one <recording_dir>/sim_config.yaml names). Ok with
/// *note set (and *scene untouched) when there is none to load; an error only for a sim_config.yaml that exists
/// and does not read.
Status LoadRunScene(const std::string& recording_dir, const std::string& scene_name_or_path, sim::Scene* scene,
                    std::string* note) {
  std::string scene_name = scene_name_or_path;
  if (scene_name.empty()) {
    const std::string config_path = recording_dir + "/sim_config.yaml";
    if (!fs::exists(config_path)) {
      *note = "the recording has no sim_config.yaml naming its scene";
      return Status::Ok();
    }
    sim::SimConfig config = sim::DefaultSimConfig();
    if (Status s = sim::LoadSimConfig(config_path, &config); !s) return s;
    scene_name = config.scene;
  }
  if (Status s = sim::LoadScene(sim::ResolveScenePath(scene_name), scene); !s)
    *note = "scene '" + scene_name + "' does not load: " + s.message;
  return Status::Ok();
}

/// Map metrics of out->map_points (scene frame) against the run's scene.
Status EvaluateMap(const sim::Scene& scene, const RunEvaluationOptions& options, RunEvaluation* out) {
  out->scene_name = scene.name;
  MapMetricsConfig config = options.map;
  config.keep_per_point = true;
  config.keep_samples = true;
  if (options.completeness)
    for (const StampedPose& p : out->truth) config.viewpoints_world.push_back(p.T_ref_body.translation());
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = ComputeMapMetrics(scene, out->map_points, config, &out->map, MakeProgressPrinter("visibility"));
      !s)
    return s;
  out->map_config = config;
  out->map_metrics_wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  LOG_INFO("map metrics: " << out->map_points.size() << " points, " << out->map.surface_samples
                            << " surface samples, " << config.viewpoints_world.size() << " viewpoints, "
                            << out->map_metrics_wall_s << " s");
  out->has_map_metrics = true;
  return Status::Ok();
}

/// The dynamic-object share of out->map_points (scene frame) against `hits`; the static surface is the scene's
/// static mesh. `scene` is null when it did not load (`scene_note` says why): a note then, unless there are no
/// hits (no map point is asked about).
Status EvaluateDynamic(const std::vector<sim::DynamicHitSample>& hits, const sim::Scene* scene,
                       const std::string& scene_note, const RunEvaluationOptions& options, RunEvaluation* out) {
  std::unique_ptr<SurfaceDistance> surface;
  StaticDistanceFn static_distance = [](const Eigen::Vector3d&, double at_least_m) { return 2.0 * at_least_m; };
  if (!hits.empty()) {
    if (!scene) {
      out->dynamic_note = "no dynamic share: " + scene_note;
      return Status::Ok();
    }
    if (Status s = SurfaceDistance::Create(sim::BuildMesh(*scene), &surface); !s) return s;
    static_distance = StaticDistanceOf(*surface);
  }
  if (Status s = ComputeDynamicShare(hits, out->map_points, static_distance, options.dynamic, &out->dynamic); !s)
    return s;
  for (DynamicObjectShare& o : out->dynamic.per_object)
    if (scene && size_t(o.object_id) < scene->dynamic_objects.size())
      o.name = scene->dynamic_objects[size_t(o.object_id)].name;
  out->dynamic_config = options.dynamic;
  out->has_dynamic = true;
  return Status::Ok();
}

/// Map metrics (when asked for) and the dynamic share (when the truth has dynamic_hits.csv) of the non-empty map
/// in the scene frame; the scene is loaded only when one of them needs it.
Status EvaluateMapAgainstScene(const std::string& recording_dir, const std::string& scene_name_or_path,
                               const RunEvaluationOptions& options, RunEvaluation* out) {
  const bool has_hits_file = fs::exists(recording_dir + "/truth/dynamic_hits.csv");
  std::vector<sim::DynamicHitSample> hits;
  if (Status s = sim::ReadDynamicHits(recording_dir, &hits); !s) return s;
  sim::Scene scene;
  std::string scene_note;
  if (options.map_metrics || !hits.empty())
    if (Status s = LoadRunScene(recording_dir, scene_name_or_path, &scene, &scene_note); !s) return s;
  const sim::Scene* loaded = scene_note.empty() ? &scene : nullptr;
  if (!options.map_metrics)
    out->map_note = "map metrics not computed (`rotolidar slam --score` or `rotolidar mapeval` compute them)";
  else if (!loaded)
    out->map_note = "no map metrics: " + scene_note;
  else if (Status s = EvaluateMap(scene, options, out); !s)
    return s;
  if (!has_hits_file) {
    out->dynamic_note = "no dynamic share: the truth has no dynamic_hits.csv (a recording from before it)";
    return Status::Ok();
  }
  return EvaluateDynamic(hits, loaded, scene_note, options, out);
}

}  // namespace

bool RunEvaluationOptions::Validate(std::string* error) const {
  if (!(rpe_delta_m > 0) || !std::isfinite(rpe_delta_m)) {
    *error = "rpe_delta_m must be > 0 and finite";
    return false;
  }
  if (rpe_fallback_frames < 1) {
    *error = "rpe_fallback_frames must be >= 1";
    return false;
  }
  if (!map.Validate(error)) {
    *error = "map: " + *error;
    return false;
  }
  if (!dynamic.Validate(error)) return false;  // names dynamic.<field>
  return true;
}

Status EvaluateRun(const std::string& recording_dir, const std::string& slam_dir, const SlamRunResult& slam,
                   const std::string& scene_name_or_path, const RunEvaluationOptions& options, RunEvaluation* out) {
  *out = RunEvaluation{};
  std::string why;
  if (!options.Validate(&why)) return Status::Error("run evaluation: " + why);
  if (Status s = EvaluateTrajectory(recording_dir, slam, options, out); !s) return s;
  if (!out->has_truth) out->deskew_note = "no deskew error: it needs the sim's truth";
  else if (Status s = EvaluateDeskewError(recording_dir, slam, out); !s) return s;
  const std::string map_path = slam_dir + "/map.ply";
  if (!fs::exists(map_path)) {
    out->map_note = "no map (" + map_path + " does not exist)";
    out->dynamic_note = "no dynamic share: " + out->map_note;
    return Status::Ok();
  }
  if (Status s = LoadMapInSceneFrame(map_path, out->T_scene_map, &out->map_points); !s) return s;
  out->map_in_scene_frame = out->has_truth;
  if (!out->has_truth) {
    out->map_note = "no map metrics: they need the sim's truth";
    out->dynamic_note = "no dynamic share: it needs the sim's truth";
    return Status::Ok();
  }
  if (out->map_points.empty()) {
    out->map_note = options.map_metrics
                        ? "no map metrics: the map is empty"
                        : "map metrics not computed (`rotolidar slam --score` or `rotolidar mapeval` compute them)";
    out->dynamic_note = "no dynamic share: the map is empty";
    return Status::Ok();
  }
  return EvaluateMapAgainstScene(recording_dir, scene_name_or_path, options, out);
}

}  // namespace rotolidar::bench
