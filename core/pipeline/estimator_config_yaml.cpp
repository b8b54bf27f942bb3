// EstimatorConfig <-> YAML with the project's one idiom (core/io/yaml_fields.hpp): every section is described
// once, as a list of (key, field) pairs, and the generic visitors parse (strict keys), emit and name fields in
// messages from it, so parsing and the resolved-config output cannot drift.
#include "core/pipeline/estimator_config_yaml.hpp"

#include "core/io/yaml_fields.hpp"

namespace rotolidar {

// Enum words and field lists live in namespace rotolidar, beside the types, so the generic visitors find them.
const yaml::EnumWordList<RobustLoss>& EnumWords(RobustLoss*) {
  static const yaml::EnumWordList<RobustLoss> words{
      {"none", RobustLoss::kNone}, {"huber", RobustLoss::kHuber}, {"cauchy", RobustLoss::kCauchy}};
  return words;
}
const yaml::EnumWordList<BackendLoss>& EnumWords(BackendLoss*) {
  static const yaml::EnumWordList<BackendLoss> words{
      {"none", BackendLoss::kNone}, {"huber", BackendLoss::kHuber}, {"cauchy", BackendLoss::kCauchy}};
  return words;
}
const yaml::EnumWordList<MarginalizationScheme>& EnumWords(MarginalizationScheme*) {
  static const yaml::EnumWordList<MarginalizationScheme> words{
      {"schur_complement", MarginalizationScheme::kSchurComplement},
      {"drop_oldest", MarginalizationScheme::kDropOldest}};
  return words;
}

// ---- the field lists ----

template <class V>
void Visit(V& v, PacketOrderConfig& c) {
  v("window_s", &c.window_s), v("max_jump_s", &c.max_jump_s), v("confirm_packets", &c.confirm_packets);
}

template <class V>
void Visit(V& v, PreprocessConfig& c) {
  v("enable_range", &c.enable_range), v("min_range_m", &c.min_range_m), v("max_range_m", &c.max_range_m);
  v("enable_sor", &c.enable_sor), v("sor_k", &c.sor_k), v("sor_std_mul", &c.sor_std_mul);
  v("sor_range_normalized", &c.sor_range_normalized), v("enable_voxel", &c.enable_voxel), v("voxel_m", &c.voxel_m);
}

template <class V>
void Visit(V& v, FeatureConfig& c) {
  v("sectors", &c.sectors), v("edges_per_sector", &c.edges_per_sector);
  v("planars_per_sector", &c.planars_per_sector), v("less_sharp_per_sector", &c.less_sharp_per_sector);
  v("planar_voxel_m", &c.planar_voxel_m);
  v("neighbours", &c.neighbours), v("edge_threshold", &c.edge_threshold), v("planar_threshold", &c.planar_threshold);
  v("range_sigma_m", &c.range_sigma_m), v("edge_min_snr", &c.edge_min_snr);
  v("range_sigma_incidence_exponent", &c.range_sigma_incidence_exponent);
  v("range_sigma_min_cos", &c.range_sigma_min_cos);
  v("max_neighbour_step_deg", &c.max_neighbour_step_deg), v("reject_occluded", &c.reject_occluded);
  v("occlusion_min_jump_m", &c.occlusion_min_jump_m), v("occlusion_jump_ratio", &c.occlusion_jump_ratio);
  v("reject_beam_parallel", &c.reject_beam_parallel);
  v("beam_parallel_max_incidence_deg", &c.beam_parallel_max_incidence_deg);
  v("less_flat_voxel_m", &c.less_flat_voxel_m), v("threads", &c.threads);
}

template <class V>
void Visit(V& v, ScanToMapConfig& c) {
  v("max_solver_iterations", &c.max_solver_iterations), v("max_correspondence_rebuilds", &c.max_correspondence_rebuilds);
  v("num_neighbours", &c.num_neighbours), v("max_neighbour_distance_m", &c.max_neighbour_distance_m);
  v("neighbour_reuse_m", &c.neighbour_reuse_m);
  v("min_line_eigen_ratio", &c.min_line_eigen_ratio), v("max_plane_eigen_ratio", &c.max_plane_eigen_ratio);
  v("max_plane_deviation_m", &c.max_plane_deviation_m), v("loss", &c.loss), v("loss_scale_m", &c.loss_scale_m);
  v("plane_incidence_exponent", &c.plane_incidence_exponent);
  v("plane_incidence_min_cos", &c.plane_incidence_min_cos);
  v("convergence_translation_m", &c.convergence_translation_m);
  v("convergence_rotation_rad", &c.convergence_rotation_rad);
  v("min_correspondences", &c.min_correspondences), v("num_threads", &c.num_threads);
  v("visibility_check", &c.visibility_check);
  v("degeneracy_remap", &c.degeneracy.remap), v("degeneracy_min_eigenvalue", &c.degeneracy.min_eigenvalue);
  v("degeneracy_weak_eigenvalue", &c.degeneracy.weak_eigenvalue), v("degeneracy_weak_gate_m", &c.degeneracy.weak_gate_m);
}

template <class V>
void Visit(V& v, LocalMapConfig& c) {
  v("keyframe_distance_m", &c.keyframe_distance_m), v("keyframe_angle_rad", &c.keyframe_angle_rad);
  v("max_keyframes", &c.max_keyframes), v("max_distance_m", &c.max_distance_m);
  v("edge_voxel_m", &c.edge_voxel_m), v("planar_voxel_m", &c.planar_voxel_m);
}

template <class V>
void Visit(V& v, FreeSpaceConfig& c) {
  v("enabled", &c.enabled), v("delay_s", &c.delay_s), v("window_s", &c.window_s);
  v("bins_per_face", &c.bins_per_face), v("margin_m", &c.margin_m), v("margin_per_m", &c.margin_per_m);
  v("min_later_through", &c.min_later_through), v("vote_every_scans", &c.vote_every_scans);
  v("min_looked_bins", &c.min_looked_bins), v("screen_scan_features", &c.screen_scan_features);
  v("recheck_s", &c.recheck_s), v("recheck_min_through", &c.recheck_min_through);
  v("recheck_max_range_m", &c.recheck_max_range_m), v("vacated_radius_m", &c.vacated_radius_m);
  v("vacated_min_age_s", &c.vacated_min_age_s), v("vacated_max_age_s", &c.vacated_max_age_s);
  v("vacated_max_share", &c.vacated_max_share);
}

}  // namespace rotolidar

namespace rotolidar::graph {  // beside the type, for argument-dependent lookup

template <class V>
void Visit(V& v, LoopClosureConfig& c) {
  v("enabled", &c.enabled), v("threaded", &c.threaded);
  v("keyframe_spacing_m", &c.keyframe_spacing_m), v("keyframe_spacing_rad", &c.keyframe_spacing_rad);
  v("cloud_voxel_m", &c.cloud_voxel_m), v("map_voxel_m", &c.map_voxel_m), v("max_range_m", &c.max_range_m);
  v("exclude_recent_s", &c.exclude_recent_s), v("min_travel_m", &c.min_travel_m);
  v("num_candidates", &c.num_candidates), v("max_descriptor_distance", &c.max_descriptor_distance);
  v("descriptor_window_s", &c.descriptor_window_s);
  v("submap_neighbours", &c.submap_neighbours), v("after_loop_travel_m", &c.after_loop_travel_m);
  v("max_guess_offset_m", &c.max_guess_offset_m), v("max_guess_offset_per_m", &c.max_guess_offset_per_m);
  v("max_guess_offset_rad", &c.max_guess_offset_rad), v("max_revisit_distance_m", &c.max_revisit_distance_m);
  v("max_loop_distance_m", &c.max_loop_distance_m);
  v("odometry_sigma_m", &c.odometry_sigma_m), v("odometry_sigma_per_m", &c.odometry_sigma_per_m);
  v("odometry_sigma_rad", &c.odometry_sigma_rad), v("odometry_sigma_per_rad", &c.odometry_sigma_per_rad);
  v("max_keyframes", &c.max_keyframes);
  v("vocabulary", yaml::Path(&c.vocabulary)), v("max_camera_offset_s", &c.max_camera_offset_s);
  v("orb_max_features", &c.orb.max_features), v("bow_min_normalised_score", &c.bow.min_normalised_score);
  v("bow_min_raw_score", &c.bow.min_raw_score);
  v("descriptor_max_radius_m", &c.descriptor.max_radius_m);
  v("verify_min_overlap", &c.verification.min_overlap);
  v("verify_max_fitness_rmse_m", &c.verification.max_fitness_rmse_m);
  v("graph_loop_rejection_chi2", &c.graph.loop_rejection_chi2);
}

}  // namespace rotolidar::graph

namespace rotolidar {

template <class V>
void Visit(V& v, SlidingWindowConfig& c) {
  v("window_size", &c.window_size), v("marginalization", &c.marginalization);
  v("estimate_gravity", &c.estimate_gravity);
  v("gravity_random_walk_rad_per_sqrt_s", &c.gravity_random_walk_rad_per_sqrt_s);
  v("initial_gravity_sigma_rad", &c.initial_gravity_sigma_rad);
  v("estimate_rotor_offset", &c.estimate_rotor_offset);
  v("rotor_offset_random_walk_rad_per_sqrt_s", &c.rotor_offset_random_walk_rad_per_sqrt_s);
  v("initial_rotor_offset_sigma_rad", &c.initial_rotor_offset_sigma_rad);
  v("estimate_time_offset", &c.estimate_time_offset);
  v("time_offset_random_walk_s_per_sqrt_s", &c.time_offset_random_walk_s_per_sqrt_s);
  v("initial_time_offset_sigma_s", &c.initial_time_offset_sigma_s);
  v("max_iterations", &c.max_iterations), v("initial_trust_region_radius", &c.initial_trust_region_radius);
  v("max_solver_time_s", &c.max_solver_time_s), v("function_tolerance", &c.function_tolerance);
  v("gradient_tolerance", &c.gradient_tolerance), v("parameter_tolerance", &c.parameter_tolerance);
  v("num_threads", &c.num_threads), v("lidar_loss", &c.lidar_loss), v("lidar_loss_scale", &c.lidar_loss_scale);
  v("repropagate_gyro_bias_radps", &c.repropagate_gyro_bias_radps);
  v("repropagate_accel_bias_mps2", &c.repropagate_accel_bias_mps2);
  v("initial_position_sigma_m", &c.initial_position_sigma_m);
  v("initial_rotation_sigma_rad", &c.initial_rotation_sigma_rad);
  v("initial_velocity_sigma_mps", &c.initial_velocity_sigma_mps);
  v("initial_gyro_bias_sigma_radps", &c.initial_gyro_bias_sigma_radps);
  v("initial_accel_bias_sigma_mps2", &c.initial_accel_bias_sigma_mps2);
  v("max_dt_mismatch_s", &c.max_dt_mismatch_s);
}

template <class V>
void Visit(V& v, ImuInitConfig& c) {
  v("gravity_mps2", &c.gravity_mps2), v("static_window_s", &c.static_window_s);
  v("static_min_samples", &c.static_min_samples), v("static_block_s", &c.static_block_s);
  v("static_max_gyro_std_radps", &c.static_max_gyro_std_radps);
  v("static_max_accel_std_mps2", &c.static_max_accel_std_mps2);
  v("still_max_gyro_mean_radps", &c.still_max_gyro_mean_radps);
  v("max_gravity_error_mps2", &c.max_gravity_error_mps2), v("moving_min_poses", &c.moving_min_poses);
  v("gyro_bias_iterations", &c.gyro_bias_iterations);
  v("gravity_refine_iterations", &c.gravity_refine_iterations);
}

// The visual module's configs live in rotolidar::visual: their field lists too, for the visitors' lookup.
namespace visual {

template <class V>
void Visit(V& v, FeatureTrackerConfig& c) {
  v("max_features", &c.max_features), v("min_distance_px", &c.min_distance_px);
  v("klt_window_px", &c.klt_window_px), v("klt_max_level", &c.klt_max_level);
  v("klt_max_iterations", &c.klt_max_iterations), v("klt_epsilon_px", &c.klt_epsilon_px);
  v("border_px", &c.border_px), v("fb_threshold_px", &c.fb_threshold_px);
  v("ransac_threshold_px", &c.ransac_threshold_px), v("ransac_confidence", &c.ransac_confidence);
  v("ransac_max_iterations", &c.ransac_max_iterations), v("ransac_min_matches", &c.ransac_min_matches);
  v("corner_quality", &c.corner_quality), v("corner_block_px", &c.corner_block_px);
  v("detect_level", &c.detect_level);
  v("grid_rows", &c.grid_rows), v("grid_cols", &c.grid_cols);
}

template <class V>
void Visit(V& v, LidarDepthConfig& c) {
  v("search_radius_deg", &c.search_radius_deg), v("max_neighbours", &c.max_neighbours);
  v("min_neighbours", &c.min_neighbours), v("max_depth_spread_m", &c.max_depth_spread_m);
  v("min_bearing_spread_deg", &c.min_bearing_spread_deg), v("max_plane_rms_m", &c.max_plane_rms_m);
  v("min_incidence_deg", &c.min_incidence_deg), v("min_depth_m", &c.min_depth_m), v("max_depth_m", &c.max_depth_m);
}

}  // namespace visual

template <class V>
void Visit(V& v, VisualWindowConfig& c) {
  v("pixel_sigma_px", &c.pixel_sigma_px), v("huber_sigmas", &c.huber_sigmas);
  v("min_observations", &c.min_observations), v("min_depth_m", &c.min_depth_m), v("max_depth_m", &c.max_depth_m);
  v("max_reprojection_px", &c.max_reprojection_px), v("initial_depth_m", &c.initial_depth_m);
  v("fix_lidar_depth", &c.fix_lidar_depth), v("max_landmarks", &c.max_landmarks);
  v("lidar_depth_sigma_m", &c.lidar_depth_sigma_m), v("lidar_depth_sigma_per_m", &c.lidar_depth_sigma_per_m);
  v("adaptive_sigma", &c.adaptive_sigma), v("max_pixel_sigma_px", &c.max_pixel_sigma_px);
  v("sigma_smoothing", &c.sigma_smoothing), v("min_residuals_for_sigma", &c.min_residuals_for_sigma);
  v("estimate_time_offset", &c.estimate_time_offset);
  v("time_offset_prior_sigma_s", &c.time_offset_prior_sigma_s);
}

template <class V>
void Visit(V& v, VisualConfig& c) {
  v("enabled", &c.enabled), v("max_image_offset_s", &c.max_image_offset_s), v("depth_cloud_s", &c.depth_cloud_s);
  v("depth_cloud_max_range_m", &c.depth_cloud_max_range_m), v("max_tracking_rate_hz", &c.max_tracking_rate_hz);
  v("depth_view_margin_rad", &c.depth_view_margin_rad), v("track_in_thread", &c.track_in_thread);
  v("registration_weak_gate_m", &c.registration_weak_gate_m);
  v("tracker", &c.tracker), v("landmarks", &c.landmarks), v("depth", &c.depth);
}

template <class V>
void Visit(V& v, EstimatorConfig& c) {
  v("cut_azimuth_deg", &c.cut_azimuth_deg), v("packet_order", &c.packet_order);
  v("keyframe_every_scans", &c.keyframe_every_scans);
  v("initial_keyframes", &c.initial_keyframes);
  v("use_imu", &c.use_imu), v("lidar_point_sigma_m", &c.lidar_point_sigma_m);
  v("lidar_only_weak_gate_m", &c.lidar_only_weak_gate_m);
  v("lidar_only_velocity_window_s", &c.lidar_only_velocity_window_s);
  v("lidar_only_max_correspondence_rebuilds", &c.lidar_only_max_correspondence_rebuilds);
  v("hold_static_start", &c.hold_static_start);
  v("imu_init_scans", &c.imu_init_scans), v("unconverged_information_scale", &c.unconverged_information_scale);
  v("output_map_voxel_m", &c.output_map_voxel_m), v("output_map_points_per_voxel", &c.output_map_points_per_voxel);
  v("output_map_max_range_m", &c.output_map_max_range_m), v("free_space", &c.free_space);
  v("loop_closure", &c.loop_closure), v("visual", &c.visual);
  v("keep_deskewed", &c.keep_deskewed);
  v("preprocess", &c.preprocess), v("features", &c.features), v("registration", &c.registration);
  v("local_map", &c.local_map), v("window", &c.window), v("imu_init", &c.imu_init);
}

Status ParseEstimatorConfig(const std::string& f, const YAML::Node& n, EstimatorConfig* c) {
  try {
    yaml::Parse(yaml::Section{f, "slam"}, n, c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {  // what a field reader did not foresee: still a message, never a crash
    return Status::Error(f + ": " + e.what());
  }
  std::string why;
  if (!c->Validate(&why)) return Status::Error(yaml::Where(f, n) + "slam: " + why);
  return Status::Ok();
}

void EmitEstimatorConfig(YAML::Emitter& out, const EstimatorConfig& config) { yaml::Emit(out, config); }

}  // namespace rotolidar
