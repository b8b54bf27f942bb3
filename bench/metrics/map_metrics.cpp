#include "bench/metrics/map_metrics.hpp"

#include <cmath>
#include <cstdio>
#include <memory>
#include <ostream>

#include <nlohmann/json.hpp>

#include "bench/eval/alignment.hpp"
#include "bench/eval/trajectory_lookup.hpp"
#include "bench/metrics/surface_distance.hpp"
#include "core/io/point_cloud_io.hpp"

namespace rotolidar::bench {
namespace {

// Viewpoints thinned so that consecutive kept ones are at least spacing_m apart.
std::vector<Eigen::Vector3d> ThinViewpoints(const std::vector<Eigen::Vector3d>& in, double spacing_m) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : in)
    if (out.empty() || (p - out.back()).norm() >= spacing_m) out.push_back(p);
  return out;
}

DistanceStats Stats(const std::vector<double>& d, double within_m) {
  DistanceStats s;
  s.count = d.size();
  if (d.empty()) return s;
  double sum = 0, sum2 = 0;
  size_t within = 0;
  for (double v : d) {
    sum += v, sum2 += v * v;
    s.max_m = std::max(s.max_m, v);
    if (v <= within_m) ++within;
  }
  const double n = static_cast<double>(d.size());
  s.mean_m = sum / n;
  s.rmse_m = std::sqrt(sum2 / n);
  s.median_m = Quantile(d, 0.5);
  s.p95_m = Quantile(d, 0.95);
  s.fraction_within_m = static_cast<double>(within) / n;
  return s;
}

Status MapToTruthDistances(const sim::TriangleMesh& mesh, const std::vector<Eigen::Vector3f>& map_world,
                           std::vector<double>* distances) {
  std::unique_ptr<SurfaceDistance> surface;
  if (Status s = SurfaceDistance::Create(mesh, &surface); !s) return s;
  distances->resize(map_world.size());
  for (size_t i = 0; i < map_world.size(); ++i) (*distances)[i] = surface->Distance(map_world[i].cast<double>());
  return Status::Ok();
}

nlohmann::json ClassJson(const ClassCoverage& c, bool visibility) {
  nlohmann::json j = {{"area_m2", c.area_m2}, {"covered_area_m2", c.covered_area_m2}, {"coverage", c.coverage}};
  if (visibility) {
    j["visible_area_m2"] = c.visible_area_m2;
    j["completeness"] = c.completeness;
  }
  return j;
}

}  // namespace

bool MapMetricsConfig::Validate(std::string* error) const {
  auto fail = [&](const char* what) { return (*error = std::string("map metrics: ") + what), false; };
  if (!(coverage_distance_m > 0)) return fail("coverage_distance_m must be > 0");
  if (!(sample_spacing_m > 0)) return fail("sample_spacing_m must be > 0");
  if (!(density_cell_m > sample_spacing_m)) return fail("density_cell_m must be > sample_spacing_m");
  if (!(visibility_min_range_m >= 0 && visibility_max_range_m > visibility_min_range_m))
    return fail("visibility range must satisfy 0 <= min < max");
  if (!(viewpoint_spacing_m >= 0)) return fail("viewpoint_spacing_m must be >= 0");
  for (const Eigen::Vector3d& v : viewpoints_world)
    if (!v.allFinite()) return fail("viewpoints_world holds a non-finite point");
  return elements.Validate(error);
}

Status ComputeMapMetrics(const sim::Scene& scene, const std::vector<Eigen::Vector3f>& map_world,
                         const MapMetricsConfig& config, MapMetrics* out,
                         const std::function<void(double)>& progress) {
  std::string why;
  if (!config.Validate(&why)) return Status::Error(why);
  if (map_world.empty()) return Status::Error("map metrics: the map has no points");
  *out = MapMetrics();
  out->map_points = map_world.size();
  const sim::TriangleMesh mesh = sim::BuildMesh(scene);
  if (mesh.triangles.empty()) return Status::Error("map metrics: scene '" + scene.name + "' has no triangles");

  std::vector<SurfaceSample> samples = SampleSurfaces(mesh, config.sample_spacing_m, config.region);
  const bool visibility = !config.viewpoints_world.empty();
  if (visibility) {
    const auto viewpoints = ThinViewpoints(config.viewpoints_world, config.viewpoint_spacing_m);
    if (Status s = MarkVisible(mesh, viewpoints, config.visibility_min_range_m, config.visibility_max_range_m,
                               &samples, progress); !s)
      return s;
  }
  MarkCovered(map_world, config.coverage_distance_m, &samples);
  out->surface_samples = samples.size();
  out->coverage = SummarizeCoverage(samples, visibility);
  out->density = ComputeDensity(samples, map_world, config.coverage_distance_m, config.density_cell_m);

  std::vector<double> distances;
  if (Status s = MapToTruthDistances(mesh, map_world, &distances); !s) return s;
  out->map_to_truth = Stats(distances, config.coverage_distance_m);
  if (config.keep_per_point) out->point_distance_m.assign(distances.begin(), distances.end());
  if (config.keep_samples) out->samples = std::move(samples);

  if (config.compute_elements) {
    for (const sim::AnnotatedElement& e : scene.elements)
      out->elements.push_back(MeasureElement(scene, e, map_world, config.elements));
    out->element_summary = SummarizeElements(out->elements);
  }
  return Status::Ok();
}

void ToJson(const MapMetrics& m, nlohmann::json* out) {
  nlohmann::json& j = *out;
  j = nlohmann::json::object();
  j["map_points"] = m.map_points;
  j["surface_samples"] = m.surface_samples;
  const bool vis = m.coverage.has_visibility;
  nlohmann::json cov = {{"visibility", vis}, {"total", ClassJson(m.coverage.total, vis)}};
  for (int c = 0; c < kNumSurfaceClasses; ++c)
    cov[SurfaceClassName(static_cast<SurfaceClass>(c))] = ClassJson(m.coverage.per_class[c], vis);
  j["coverage"] = cov;
  const DensityResult& d = m.density;
  j["density"] = {{"cells", d.cells}, {"occupied_cells", d.occupied_cells}, {"occupied_fraction", d.occupied_fraction},
                  {"cv", d.cv}, {"mean_per_m2", d.mean_per_m2}, {"median_per_m2", d.median_per_m2},
                  {"p05_per_m2", d.p05_per_m2}, {"p95_per_m2", d.p95_per_m2}};
  const DistanceStats& t = m.map_to_truth;
  j["map_to_truth_m"] = {{"count", t.count}, {"median", t.median_m}, {"mean", t.mean_m}, {"rmse", t.rmse_m},
                         {"p95", t.p95_m}, {"max", t.max_m}, {"fraction_within_distance", t.fraction_within_m}};
  nlohmann::json elements = nlohmann::json::array();
  for (const ElementMeasurement& e : m.elements) {
    nlohmann::json je = {{"name", e.name}, {"type", e.type}, {"crop_points", e.crop_points},
                         {"true_width_m", e.true_width_m}, {"true_height_m", e.true_height_m}};
    if (e.width_measured) je["width_m"] = e.width_m, je["width_error_m"] = e.width_error_m;
    if (e.height_measured) je["height_m"] = e.height_m, je["height_error_m"] = e.height_error_m;
    if (!e.message.empty()) je["message"] = e.message;
    elements.push_back(je);
  }
  const ElementSummary& s = m.element_summary;
  j["elements"] = elements;
  j["element_errors_m"] = {{"elements", s.elements}, {"widths_measured", s.widths_measured},
                           {"heights_measured", s.heights_measured}, {"width_rmse", s.width_rmse_m},
                           {"height_rmse", s.height_rmse_m}, {"rmse", s.rmse_m}, {"max_abs", s.max_abs_error_m}};
}

void PrintMapMetrics(const MapMetrics& m, std::ostream& os) {
  char line[256];
  const bool vis = m.coverage.has_visibility;
  os << "map: " << m.map_points << " points, " << m.surface_samples << " surface samples\n";
  std::snprintf(line, sizeof(line), "%-8s %10s %10s %9s %12s\n", "surface", "area_m2", "covered_m2", "coverage",
                vis ? "completeness" : "");
  os << line;
  for (int c = 0; c <= kNumSurfaceClasses; ++c) {
    const ClassCoverage& cc = c < kNumSurfaceClasses ? m.coverage.per_class[c] : m.coverage.total;
    const char* name = c < kNumSurfaceClasses ? SurfaceClassName(static_cast<SurfaceClass>(c)) : "total";
    std::snprintf(line, sizeof(line), "%-8s %10.2f %10.2f %9.3f", name, cc.area_m2, cc.covered_area_m2, cc.coverage);
    os << line;
    if (vis) std::snprintf(line, sizeof(line), " %12.3f", cc.completeness), os << line;
    os << "\n";
  }
  const DensityResult& d = m.density;
  std::snprintf(line, sizeof(line), "density : CV %.3f over %zu occupied of %zu cells; median %.0f, p5 %.0f, p95 %.0f "
                "points/m2\n", d.cv, d.occupied_cells, d.cells, d.median_per_m2, d.p05_per_m2, d.p95_per_m2);
  os << line;
  const DistanceStats& t = m.map_to_truth;
  std::snprintf(line, sizeof(line), "map-to-truth [m]: median %.4f mean %.4f rmse %.4f p95 %.4f max %.4f (%.1f%% within "
                "the coverage distance)\n", t.median_m, t.mean_m, t.rmse_m, t.p95_m, t.max_m, 100 * t.fraction_within_m);
  os << line;
  if (m.elements.empty()) return;
  std::snprintf(line, sizeof(line), "%-18s %-7s %8s %8s %8s %8s %8s %8s %7s\n", "element", "type", "w_true", "w_meas",
                "w_err", "h_true", "h_meas", "h_err", "points");
  os << line;
  for (const ElementMeasurement& e : m.elements) {
    auto value = [](bool ok, double v) {
      char b[32];
      if (ok) std::snprintf(b, sizeof(b), "%8.3f", v);
      else std::snprintf(b, sizeof(b), "%8s", "-");
      return std::string(b);
    };
    std::snprintf(line, sizeof(line), "%-18s %-7s %8.3f %s %s %8.3f %s %s %7zu", e.name.c_str(), e.type.c_str(),
                  e.true_width_m, value(e.width_measured, e.width_m).c_str(),
                  value(e.width_measured, e.width_error_m).c_str(), e.true_height_m,
                  value(e.height_measured, e.height_m).c_str(), value(e.height_measured, e.height_error_m).c_str(),
                  e.crop_points);
    os << line << (e.message.empty() ? "" : "  (" + e.message + ")") << "\n";
  }
  const ElementSummary& s = m.element_summary;
  std::snprintf(line, sizeof(line), "elements: RMSE %.4f m (width %.4f over %zu, height %.4f over %zu), max |error| "
                "%.4f m\n", s.rmse_m, s.width_rmse_m, s.widths_measured, s.height_rmse_m, s.heights_measured,
                s.max_abs_error_m);
  os << line;
}

bool ParseMapAlignment(const std::string& name, MapAlignment* out) {
  if (name == "first") return (*out = MapAlignment::kFirstPose), true;
  if (name == "se3") return (*out = MapAlignment::kSe3), true;
  return false;
}

Status MapToSceneTransform(const Trajectory& truth, const Trajectory& estimate, MapAlignment alignment,
                           Eigen::Isometry3d* T_scene_slam) {
  if (estimate.empty()) return Status::Error("map alignment: the estimated trajectory is empty");
  if (alignment == MapAlignment::kFirstPose) {
    const Trajectory at = InterpolateTrajectory(truth, Trajectory{estimate.front()});
    if (at.empty()) return Status::Error("map alignment: the truth does not cover the estimate's first stamp");
    *T_scene_slam = at.front().T_ref_body * estimate.front().T_ref_body.inverse();
    return Status::Ok();
  }
  const Trajectory ref = InterpolateTrajectory(truth, estimate);
  std::vector<Eigen::Vector3d> p_ref, p_est;
  size_t k = 0;
  for (const StampedPose& r : ref) {  // both sorted by time: pair the estimate pose with the same stamp
    while (k < estimate.size() && estimate[k].t_s < r.t_s) ++k;
    if (k == estimate.size()) break;
    p_ref.push_back(r.T_ref_body.translation());
    p_est.push_back(estimate[k].T_ref_body.translation());
  }
  const AlignmentResult a = AlignPositions(p_est, p_ref, Alignment::kSe3);
  if (!a.success) return Status::Error("map alignment: " + a.message);
  *T_scene_slam = a.T_ref_est;
  return Status::Ok();
}

Status LoadMapInSceneFrame(const std::string& path, const Eigen::Isometry3d& T_scene_map,
                           std::vector<Eigen::Vector3f>* map_world) {
  std::vector<Eigen::Vector3d> points;
  if (Status s = LoadPointCloud(path, &points); !s) return s;
  map_world->clear();
  map_world->reserve(points.size());
  for (const Eigen::Vector3d& p : points) map_world->push_back((T_scene_map * p).cast<float>());
  return Status::Ok();
}

}  // namespace rotolidar::bench
