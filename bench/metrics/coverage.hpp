#pragma once
// Surface coverage of a map against the scene's triangles (docs/metrics.md "Coverage", "Density uniformity").
//
// The scene's static surfaces are sampled on a fixed grid per triangle (deterministic, area-uniform: each
// sample stands for its triangle's area / its sample count, so weights sum to the surface area exactly). A
// sample is covered when a map point lies within a distance of it (PCL kd-tree of the map). Optionally a
// sample is visible when a viewpoint sees it (Embree line of sight, within a range band); completeness is the
// covered share of the visible area. All positions in the scene's world frame [m].
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/util/status.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::bench {

/// By the triangle's front normal n (unit): n_z > 0.9 floor (any upward-facing horizontal surface, table tops
/// included), n_z < -0.9 ceiling (downward-facing), |n_z| < 0.3 wall, else other (slopes, ramps, facets).
enum class SurfaceClass : uint8_t { kWall = 0, kFloor = 1, kCeiling = 2, kOther = 3 };
constexpr int kNumSurfaceClasses = 4;
const char* SurfaceClassName(SurfaceClass c);  ///< "wall", "floor", "ceiling", "other"
SurfaceClass ClassifyNormal(const Eigen::Vector3d& unit_normal);

struct SurfaceSample {
  Eigen::Vector3f p_world = Eigen::Vector3f::Zero();  ///< on the triangle [m]
  float area_m2 = 0.0f;  ///< surface area this sample stands for
  SurfaceClass surface_class = SurfaceClass::kOther;
  int triangle_id = -1;  ///< index into the TriangleMesh it came from
  bool covered = false;  ///< a map point within the coverage distance
  bool visible = true;   ///< seen from a viewpoint (true when visibility was not computed)
};

/// Samples every triangle on a grid of `spacing_m` in its own plane (cell centres inside the triangle; a
/// triangle smaller than one cell gets its centroid). Keeps samples inside `region` (empty box = all).
/// spacing_m must be > 0 (programmer error otherwise).
std::vector<SurfaceSample> SampleSurfaces(const sim::TriangleMesh& mesh, double spacing_m,
                                          const Eigen::AlignedBox3d& region);

/// Sets `covered` on each sample that has a map point within distance_m (PCL kd-tree). An empty map leaves
/// every sample uncovered.
void MarkCovered(const std::vector<Eigen::Vector3f>& map_world, double distance_m,
                 std::vector<SurfaceSample>* samples);

/// Sets `visible` = some viewpoint lies within [min_range_m, max_range_m] of the sample and the ray from the
/// viewpoint to the sample reaches it (first hit within 5 mm of the sample). Rays go against `mesh` (static
/// world). Fails on an Embree error or an empty mesh. Samples are grouped in 2 m tiles; each tile tries only
/// the viewpoints that can be in range, nearest first, and tiles run on all hardware threads (the flags do
/// not depend on the order or the thread count). `progress` (optional) gets the finished fraction in [0, 1],
/// from one thread at a time.
Status MarkVisible(const sim::TriangleMesh& mesh, const std::vector<Eigen::Vector3d>& viewpoints_world,
                   double min_range_m, double max_range_m, std::vector<SurfaceSample>* samples,
                   const std::function<void(double)>& progress = nullptr);

struct ClassCoverage {
  double area_m2 = 0.0;                  ///< sampled surface area
  double covered_area_m2 = 0.0;
  double coverage = 0.0;                 ///< covered / area; 0 when area is 0
  double visible_area_m2 = 0.0;          ///< area of visible samples (= area without visibility)
  double covered_visible_area_m2 = 0.0;
  double completeness = 0.0;             ///< covered visible / visible; 0 when visible area is 0
};

struct CoverageResult {
  std::array<ClassCoverage, kNumSurfaceClasses> per_class;  ///< indexed by SurfaceClass
  ClassCoverage total;
  bool has_visibility = false;  ///< completeness is meaningful only when true
};

CoverageResult SummarizeCoverage(const std::vector<SurfaceSample>& samples, bool has_visibility);

/// Point density over surface cells: each map point within distance_m of a sample counts in that sample's
/// cell (cubes of cell_m); a cell's density = its points / its (visible) sample area. Cells with less than
/// a quarter of cell_m^2 of (visible) surface are left out. CV = std / mean over occupied cells.
struct DensityResult {
  size_t cells = 0;           ///< cells with enough (visible) surface
  size_t occupied_cells = 0;  ///< of those, cells with at least one point
  double occupied_fraction = 0.0;
  double cv = 0.0;            ///< coefficient of variation of density over occupied cells
  double mean_per_m2 = 0.0, median_per_m2 = 0.0, p05_per_m2 = 0.0, p95_per_m2 = 0.0;
};

/// The q-quantile (q in [0, 1]) of values with linear interpolation between order statistics (numpy's
/// default); 0 for an empty vector.
double Quantile(std::vector<double> values, double q);

DensityResult ComputeDensity(const std::vector<SurfaceSample>& samples,
                             const std::vector<Eigen::Vector3f>& map_world, double distance_m, double cell_m);

}  // namespace rotolidar::bench
