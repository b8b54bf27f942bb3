#include "core/io/config_yaml.hpp"

#include "core/io/yaml_util.hpp"

namespace rotolidar {

Status ParseEstimatorConfig(const std::string& f, const YAML::Node& n, EstimatorConfig* c) {
  using yaml::Get;
  try {
    yaml::CheckKeys(f, n,
                    {"min_range_m", "max_range_m", "scan_voxel_m", "cut_azimuth_deg", "local_map_voxel_m",
                     "local_map_points_per_voxel", "local_map_radius_m", "target_refresh_scans",
                     "output_map_voxel_m", "output_map_points_per_voxel", "registration"},
                    "slam");
    Get(f, n, "min_range_m", &c->min_range_m);
    Get(f, n, "max_range_m", &c->max_range_m);
    Get(f, n, "scan_voxel_m", &c->scan_voxel_m);
    Get(f, n, "cut_azimuth_deg", &c->cut_azimuth_deg);
    Get(f, n, "local_map_voxel_m", &c->local_map_voxel_m);
    Get(f, n, "local_map_points_per_voxel", &c->local_map_points_per_voxel);
    Get(f, n, "local_map_radius_m", &c->local_map_radius_m);
    Get(f, n, "target_refresh_scans", &c->target_refresh_scans);
    Get(f, n, "output_map_voxel_m", &c->output_map_voxel_m);
    Get(f, n, "output_map_points_per_voxel", &c->output_map_points_per_voxel);
    if (const YAML::Node r = n["registration"]) {
      yaml::CheckKeys(f, r, {"max_correspondence_m", "max_iterations", "transformation_epsilon", "k_correspondences"},
                      "slam.registration");
      Get(f, r, "max_correspondence_m", &c->registration.max_correspondence_m);
      Get(f, r, "max_iterations", &c->registration.max_iterations);
      Get(f, r, "transformation_epsilon", &c->registration.transformation_epsilon);
      Get(f, r, "k_correspondences", &c->registration.k_correspondences);
    }
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  if (!c->Validate(&why)) return Status::Error(yaml::Where(f, n) + "slam: " + why);
  return Status::Ok();
}

void EmitEstimatorConfig(YAML::Emitter& out, const EstimatorConfig& c) {
  out << YAML::BeginMap;
  out << YAML::Key << "min_range_m" << YAML::Value << c.min_range_m;
  out << YAML::Key << "max_range_m" << YAML::Value << c.max_range_m;
  out << YAML::Key << "scan_voxel_m" << YAML::Value << c.scan_voxel_m;
  out << YAML::Key << "cut_azimuth_deg" << YAML::Value << c.cut_azimuth_deg;
  out << YAML::Key << "local_map_voxel_m" << YAML::Value << c.local_map_voxel_m;
  out << YAML::Key << "local_map_points_per_voxel" << YAML::Value << c.local_map_points_per_voxel;
  out << YAML::Key << "local_map_radius_m" << YAML::Value << c.local_map_radius_m;
  out << YAML::Key << "target_refresh_scans" << YAML::Value << c.target_refresh_scans;
  out << YAML::Key << "output_map_voxel_m" << YAML::Value << c.output_map_voxel_m;
  out << YAML::Key << "output_map_points_per_voxel" << YAML::Value << c.output_map_points_per_voxel;
  const ScanMatcherConfig& r = c.registration;
  out << YAML::Key << "registration" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "max_correspondence_m" << YAML::Value << r.max_correspondence_m;
  out << YAML::Key << "max_iterations" << YAML::Value << r.max_iterations;
  out << YAML::Key << "transformation_epsilon" << YAML::Value << r.transformation_epsilon;
  out << YAML::Key << "k_correspondences" << YAML::Value << r.k_correspondences;
  out << YAML::EndMap << YAML::EndMap;
}

}  // namespace rotolidar
