#include "core/features/curvature_features.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <thread>

#include "core/util/log.hpp"
#include "core/util/thread_pool.hpp"

namespace rotolidar {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Azimuth advance [deg] from a point fired earlier to one fired later on the same ring, in [0, 360).
float StepDeg(float from_deg, float to_deg) {
  const float d = to_deg - from_deg;
  return d < 0.f ? d + 360.f : d;
}

/// One ring in firing order. Stage 1 (one task per ring) fills it; stage 2 (one task per sector) reads it and
/// writes `picked` and the labels only at the positions of its own sector, so no two tasks share a written byte.
struct Ring {
  std::vector<int> index;        ///< input indices, by firing time
  std::vector<float> x, y, z, range, az;  ///< per position: p_base [m], range_m [m], azimuth_deg (contiguous copies)
  std::vector<uint8_t> step_ok;  ///< step_ok[j]: positions j and j+1 are neighbours
  std::vector<float> c;          ///< Eq. 3 per position, NaN without a window
  std::vector<int> sector;       ///< sector per position
  std::vector<int> sector_begin; ///< positions of sector s: by_sector[sector_begin[s] .. sector_begin[s + 1])
  std::vector<int> by_sector;    ///< positions grouped by sector, in firing order inside each
  std::vector<uint8_t> sharp;    ///< c above the edge threshold at the point's range (EdgeThresholdAt)
  std::vector<uint8_t> picked;   ///< LOAM's "neighbour picked": not selectable any more
};

struct Context {
  const std::vector<ScanPoint>& points;
  const FeatureConfig& config;
  std::vector<Ring> rings;
  std::vector<FeatureLabel> labels;  ///< per input point
  double tan_max_incidence = 0.0;    ///< tan(config.beam_parallel_max_incidence_deg)
  double sigma_c_numerator = 0.0;    ///< range_sigma_m * sqrt(4N^2 + 2N) (EdgeThresholdAt)
};

struct SectorOutput {
  pcl::PointCloud<pcl::PointXYZI> edge, planar, less_sharp;
  std::vector<int> less_flat;  ///< input indices: the map-side planar set before its voxel filter
};

/// Runs fn(0..n-1) on the shared pool of `threads` threads (core/util/thread_pool.hpp; started once per process,
/// not per scan). Each call must write only its own outputs.
void ParallelFor(int n, int threads, const std::function<void(int)>& fn) {
  ThreadPool::Shared(std::max(1, std::min(threads, n))).ParallelFor(n, fn);
}

/// A depth jump between two neighbouring returns (occlusion boundary or a surface almost along the beam).
bool IsDepthJump(const FeatureConfig& cfg, float r_a, float r_b) {
  const double jump = std::abs(double(r_a) - double(r_b));
  return jump > std::max(cfg.occlusion_min_jump_m, cfg.occlusion_jump_ratio * std::min(r_a, r_b));
}

/// Eq. 3 over one ring's positions (firing order); step_ok as in Ring. The window sum is
/// sum_j (X_i - X_j) = (2N + 1) X_i - sum_j X_j with the X_j summed by prefix sums in double (exact for float
/// inputs of a scan's magnitudes), so each point costs O(1) whatever N.
std::vector<float> CurvatureOf(const std::vector<float>& x, const std::vector<float>& y, const std::vector<float>& z,
                               const std::vector<float>& range, const std::vector<uint8_t>& step_ok, int n_side) {
  const int n = static_cast<int>(x.size());
  std::vector<int> bad_before(n + 1, 0);  // bad_before[j]: number of bad steps among steps 0..j-1
  for (int j = 0; j + 1 < n; ++j) bad_before[j + 1] = bad_before[j] + (step_ok[j] ? 0 : 1);
  std::vector<double> px(n + 1, 0.0), py(n + 1, 0.0), pz(n + 1, 0.0);  // prefix sums: p[j] = sum of 0..j-1
  for (int j = 0; j < n; ++j) px[j + 1] = px[j] + x[j], py[j + 1] = py[j] + y[j], pz[j + 1] = pz[j] + z[j];
  std::vector<float> c(n, kNaN);
  const double width = 2.0 * n_side + 1.0;
  for (int i = n_side; i + n_side < n; ++i) {
    if (bad_before[i + n_side] != bad_before[i - n_side]) continue;  // the window crosses a gap
    const int lo = i - n_side, hi = i + n_side + 1;
    const double sx = width * x[i] - (px[hi] - px[lo]), sy = width * y[i] - (py[hi] - py[lo]);
    const double sz = width * z[i] - (pz[hi] - pz[lo]);
    c[i] = static_cast<float>(std::sqrt(sx * sx + sy * sy + sz * sz) / (2.0 * n_side * range[i]));
  }
  return c;
}

std::vector<uint8_t> StepsOk(const std::vector<float>& az, double max_deg) {
  std::vector<uint8_t> ok(az.empty() ? 0 : az.size() - 1);
  for (std::size_t j = 0; j < ok.size(); ++j) ok[j] = StepDeg(az[j], az[j + 1]) <= max_deg;
  return ok;
}

/// LOAM's occluded-point rule: at a depth jump between neighbours, the N+1 points on the far side next to it.
void MarkOccluded(const Context& ctx, const Ring& ring, std::vector<uint8_t>* occluded) {
  const int n = static_cast<int>(ring.index.size()), n_side = ctx.config.neighbours;
  for (int j = 0; j + 1 < n; ++j) {
    if (!ring.step_ok[j]) continue;
    const float r_a = ring.range[j], r_b = ring.range[j + 1];
    if (!IsDepthJump(ctx.config, r_a, r_b)) continue;
    const int first = r_a > r_b ? j - n_side : j + 1, last = r_a > r_b ? j : j + 1 + n_side;
    for (int q = std::max(0, first); q <= std::min(n - 1, last); ++q) (*occluded)[q] = 1;
  }
}

/// tan of the surface's incidence from the range slope over N steps on each side of position i: the smaller
/// side's |slope| for the beam-parallel rule (a corner with one face square to the beam is not beam-parallel), the
/// mean of the two sides' |slope| for the noise gate. The mean reads a corner between two oblique faces as oblique,
/// and it is: the returns on both faces are noisier. (The signed central difference, which cancels at corners,
/// kept 4x more noise edges on the twin's walls and cost ATE; docs/features.md, "Oblique surfaces".)
/// Only for positions with a full window.
struct IncidenceSlopes {
  double mean = 0.0, min_side = 0.0;
};
IncidenceSlopes TanIncidence(const Context& ctx, const Ring& ring, int i) {
  const int n_side = ctx.config.neighbours;
  const double r_i = ring.range[i];
  // angles between the rays [rad] (ignore cos(elevation) <= 3.5 %)
  const double g_before = StepDeg(ring.az[i - n_side], ring.az[i]) * kDegToRad;
  const double g_after = StepDeg(ring.az[i], ring.az[i + n_side]) * kDegToRad;
  const double t_before = std::abs(double(ring.range[i]) - double(ring.range[i - n_side])) / (r_i * g_before);
  const double t_after = std::abs(double(ring.range[i + n_side]) - double(ring.range[i])) / (r_i * g_after);
  return {0.5 * (t_before + t_after), std::min(t_before, t_after)};
}

/// The edge threshold at range r [m] on a surface of incidence tan_incidence: the fixed Eq. 3 threshold or the
/// noise gate, whichever is higher. The range sigma grows as 1 / max(cos(incidence), min_cos)^exponent.
double EdgeThresholdAt(const Context& ctx, float range_m, double tan_incidence) {
  const FeatureConfig& cfg = ctx.config;
  const double cos_inc = std::max(cfg.range_sigma_min_cos, 1.0 / std::sqrt(1.0 + tan_incidence * tan_incidence));
  const double sigma_c = ctx.sigma_c_numerator / (2.0 * cfg.neighbours * range_m) /
                         std::pow(cos_inc, cfg.range_sigma_incidence_exponent);
  return std::max(cfg.edge_threshold, cfg.edge_min_snr * sigma_c);
}

/// Contiguous copies of the ring's point attributes, in its (firing) order.
void GatherRing(const std::vector<ScanPoint>& pts, Ring* ring) {
  const std::size_t n = ring->index.size();
  ring->x.resize(n), ring->y.resize(n), ring->z.resize(n), ring->range.resize(n), ring->az.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    const ScanPoint& p = pts[ring->index[j]];
    ring->x[j] = p.p_base.x(), ring->y[j] = p.p_base.y(), ring->z[j] = p.p_base.z();
    ring->range[j] = p.range_m, ring->az[j] = p.azimuth_deg;
  }
}

/// Sector of every position and the positions grouped by sector (a counting sort: firing order inside each).
void SortIntoSectors(int sectors, Ring* ring) {
  const int n = static_cast<int>(ring->index.size());
  const double sector_deg = 360.0 / sectors;
  ring->sector.resize(n);
  ring->sector_begin.assign(sectors + 1, 0);
  for (int i = 0; i < n; ++i) {
    const double q = ring->az[i] / sector_deg;  // floor(q) clamped to the sectors (truncation: no libm call)
    ring->sector[i] = q < 1.0 ? 0 : std::min(static_cast<int>(std::min(q, double(sectors))), sectors - 1);
    ++ring->sector_begin[ring->sector[i] + 1];
  }
  for (int s = 0; s < sectors; ++s) ring->sector_begin[s + 1] += ring->sector_begin[s];
  std::vector<int> fill(ring->sector_begin.begin(), ring->sector_begin.end() - 1);
  ring->by_sector.resize(n);
  for (int i = 0; i < n; ++i) ring->by_sector[fill[ring->sector[i]]++] = i;
}

// Stage 1, one ring: firing order, steps, curvature, sectors and the rejection labels.
void AnalyseRing(Context* ctx, Ring* ring) {
  const std::vector<ScanPoint>& pts = ctx->points;
  const FeatureConfig& cfg = ctx->config;
  const auto earlier = [&](int a, int b) { return pts[a].t_s < pts[b].t_s || (pts[a].t_s == pts[b].t_s && a < b); };
  if (!std::is_sorted(ring->index.begin(), ring->index.end(), earlier))  // decoded scans come in firing order
    std::sort(ring->index.begin(), ring->index.end(), earlier);
  const int n = static_cast<int>(ring->index.size());
  GatherRing(pts, ring);
  ring->step_ok = StepsOk(ring->az, cfg.max_neighbour_step_deg);
  ring->c = CurvatureOf(ring->x, ring->y, ring->z, ring->range, ring->step_ok, cfg.neighbours);
  ring->picked.assign(n, 0);
  ring->sharp.resize(n);
  SortIntoSectors(cfg.sectors, ring);
  std::vector<uint8_t> occluded(n, 0);
  if (cfg.reject_occluded) MarkOccluded(*ctx, *ring, &occluded);
  for (int i = 0; i < n; ++i) {
    FeatureLabel& label = ctx->labels[ring->index[i]];
    ring->sharp[i] = 0;
    if (std::isnan(ring->c[i])) {
      label = FeatureLabel::kNoWindow;
      continue;
    }
    const IncidenceSlopes slopes = TanIncidence(*ctx, *ring, i);  // once per point, for both rules
    ring->sharp[i] = ring->c[i] > cfg.edge_threshold &&  // the gate is never below it: skip its cost
                     ring->c[i] > EdgeThresholdAt(*ctx, ring->range[i], slopes.mean);
    if (occluded[i]) label = FeatureLabel::kOccluded;
    else if (cfg.reject_beam_parallel && slopes.min_side > ctx->tan_max_incidence)  // LOAM's beam-parallel rule
      label = FeatureLabel::kBeamParallel;
    else label = FeatureLabel::kUnused;
  }
}

/// Marks the +-N neighbours of a pick in the same sector as picked, up to a gap or a depth jump (LOAM).
void Suppress(const Context& ctx, int sector, int p, Ring* ring) {
  const int n = static_cast<int>(ring->index.size());
  for (const int dir : {-1, 1}) {
    for (int s = 1; s <= ctx.config.neighbours; ++s) {
      const int q = p + dir * s, prev = q - dir;
      if (q < 0 || q >= n || ring->sector[q] != sector || !ring->step_ok[std::min(q, prev)]) break;
      if (IsDepthJump(ctx.config, ring->range[q], ring->range[prev])) break;
      ring->picked[q] = 1;
    }
  }
}

pcl::PointXYZI ToPcl(const ScanPoint& p, float c) {
  pcl::PointXYZI out;
  out.x = p.p_base.x(), out.y = p.p_base.y(), out.z = p.p_base.z();
  out.intensity = c;
  return out;
}

/// Candidate buffers reused across the cells of one sector task.
struct CellScratch {
  std::vector<int> sharp, flat;
};

// Stage 2, one (ring, sector) cell: LOAM's selection, sharpest first, then flattest, then the less-flat set.
// The sharp candidates are sorted by c descending (ties: firing order); the flat ones are popped from a heap in
// the reverse order (c ascending, ties: later firing first), so only the few points picked are ever ordered.
// Both are heaps (make_heap is linear; only the popped few are ordered): a point that can never become an edge
// (not sharp: c below the gate at its range) is no sharp candidate, which the full sort used to skip at its turn.
void SelectCell(Context* ctx, int sector, Ring* ring, SectorOutput* out, CellScratch* scratch) {
  const FeatureConfig& cfg = ctx->config;
  const std::vector<float>& c = ring->c;
  std::vector<int>& sharp_cand = scratch->sharp;  // selectable positions of this cell
  std::vector<int>& flat_cand = scratch->flat;
  sharp_cand.clear(), flat_cand.clear();
  for (int k = ring->sector_begin[sector]; k < ring->sector_begin[sector + 1]; ++k) {
    const int i = ring->by_sector[k];
    if (ctx->labels[ring->index[i]] != FeatureLabel::kUnused) continue;
    if (ring->sharp[i]) sharp_cand.push_back(i);  // sharp implies c > edge_threshold
    if (c[i] < cfg.planar_threshold) flat_cand.push_back(i);
  }
  const auto sharper = [&](int a, int b) { return c[a] < c[b] || (c[a] == c[b] && a > b); };  // top: sharpest
  std::make_heap(sharp_cand.begin(), sharp_cand.end(), sharper);
  int n_edge = 0, n_sharp = 0, n_planar = 0;
  auto take = [&](int p, FeatureLabel label, pcl::PointCloud<pcl::PointXYZI>* cloud) {
    ctx->labels[ring->index[p]] = label;
    cloud->push_back(ToPcl(ctx->points[ring->index[p]], c[p]));
    ring->picked[p] = 1;
    Suppress(*ctx, sector, p, ring);
  };
  for (auto end = sharp_cand.end(); end != sharp_cand.begin() && n_sharp < cfg.less_sharp_per_sector; --end) {
    std::pop_heap(sharp_cand.begin(), end, sharper);  // c descending, ties: firing order
    const int p = *(end - 1);
    if (ring->picked[p]) continue;
    const bool edge = n_edge < cfg.edges_per_sector;
    take(p, edge ? FeatureLabel::kEdge : FeatureLabel::kLessSharp, &out->less_sharp);
    if (edge) {
      out->edge.push_back(out->less_sharp.back());
      ++n_edge;
    }
    ++n_sharp;
  }
  const auto after = [&](int a, int b) { return c[a] > c[b] || (c[a] == c[b] && a < b); };  // heap top: flattest
  std::make_heap(flat_cand.begin(), flat_cand.end(), after);
  for (auto end = flat_cand.end(); end != flat_cand.begin() && n_planar < cfg.planars_per_sector; --end) {
    std::pop_heap(flat_cand.begin(), end, after);
    const int p = *(end - 1);
    if (ring->picked[p]) continue;
    take(p, FeatureLabel::kPlanar, &out->planar);
    ++n_planar;
  }
  for (int k = ring->sector_begin[sector]; k < ring->sector_begin[sector + 1]; ++k) {  // firing order
    const int p = ring->by_sector[k];  // kUnused / kPlanar = selectable at the start
    FeatureLabel& label = ctx->labels[ring->index[p]];
    if ((label != FeatureLabel::kUnused && label != FeatureLabel::kPlanar) || ring->sharp[p]) continue;
    if (label == FeatureLabel::kUnused) label = FeatureLabel::kLessFlat;
    out->less_flat.push_back(ring->index[p]);
  }
}

/// The less-flat cloud: one point per voxel_m voxel (VoxelRepresentatives, in list order), all when voxel_m is 0.
pcl::PointCloud<pcl::PointXYZI> LessFlatCloud(const Context& ctx, const std::vector<int>& list,
                                              const std::vector<float>& curvature, double voxel_m) {
  pcl::PointCloud<pcl::PointXYZI> out;
  if (voxel_m <= 0.0) {
    for (const int i : list) out.push_back(ToPcl(ctx.points[i], curvature[i]));
    return out;
  }
  std::vector<Eigen::Vector3f> positions(list.size());
  for (std::size_t k = 0; k < list.size(); ++k) positions[k] = ctx.points[list[k]].p_base;
  for (const std::size_t k : VoxelRepresentatives(positions, voxel_m))
    out.push_back(ToPcl(ctx.points[list[k]], curvature[list[k]]));
  return out;
}

/// One point per voxel_m voxel of `cloud` (VoxelRepresentatives: the point nearest the centroid), in list order.
pcl::PointCloud<pcl::PointXYZI> VoxelDownsampled(const pcl::PointCloud<pcl::PointXYZI>& cloud, double voxel_m) {
  std::vector<Eigen::Vector3f> positions(cloud.size());
  for (std::size_t k = 0; k < cloud.size(); ++k) positions[k] = cloud.points[k].getVector3fMap();
  pcl::PointCloud<pcl::PointXYZI> out;
  for (const std::size_t k : VoxelRepresentatives(positions, voxel_m)) out.push_back(cloud.points[k]);
  return out;
}

FeatureStats CountLabels(const std::vector<FeatureLabel>& labels, const FeatureSet& set, std::size_t less_flat_raw) {
  FeatureStats s;
  s.num_input = labels.size();
  for (const FeatureLabel l : labels) {
    s.num_invalid += l == FeatureLabel::kInvalid;
    s.num_no_window += l == FeatureLabel::kNoWindow;
    s.num_occluded += l == FeatureLabel::kOccluded;
    s.num_beam_parallel += l == FeatureLabel::kBeamParallel;
  }
  s.num_edge = set.edge.size(), s.num_planar = set.planar.size(), s.num_less_sharp = set.less_sharp.size();
  s.num_less_flat_raw = less_flat_raw, s.num_less_flat = set.less_flat.size();
  return s;
}

}  // namespace

bool FeatureConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& field, const std::string& rule, double got) {
    if (error) {
      std::ostringstream os;
      os << "features." << field << " must be " << rule << " (got " << got << ")";
      *error = os.str();
    }
    return false;
  };
  if (sectors < 1 || sectors > 360) return fail("sectors", "in [1, 360]", sectors);
  if (edges_per_sector < 0) return fail("edges_per_sector", ">= 0", edges_per_sector);
  if (planars_per_sector < 0) return fail("planars_per_sector", ">= 0", planars_per_sector);
  if (less_sharp_per_sector < edges_per_sector)
    return fail("less_sharp_per_sector", ">= edges_per_sector", less_sharp_per_sector);
  if (neighbours < 1) return fail("neighbours", ">= 1", neighbours);
  if (!(edge_threshold > 0.0) || !std::isfinite(edge_threshold))
    return fail("edge_threshold", "finite and > 0", edge_threshold);
  if (!(planar_threshold > 0.0) || !(planar_threshold <= edge_threshold))
    return fail("planar_threshold", "> 0 and <= edge_threshold", planar_threshold);
  if (!(max_neighbour_step_deg > 0.0) || !(max_neighbour_step_deg < 180.0))
    return fail("max_neighbour_step_deg", "in (0, 180)", max_neighbour_step_deg);
  if (!(occlusion_min_jump_m >= 0.0)) return fail("occlusion_min_jump_m", ">= 0", occlusion_min_jump_m);
  if (!(occlusion_jump_ratio >= 0.0)) return fail("occlusion_jump_ratio", ">= 0", occlusion_jump_ratio);
  if (!(beam_parallel_max_incidence_deg > 0.0) || !(beam_parallel_max_incidence_deg < 90.0))
    return fail("beam_parallel_max_incidence_deg", "in (0, 90)", beam_parallel_max_incidence_deg);
  if (!(planar_voxel_m >= 0.0) || !std::isfinite(planar_voxel_m))
    return fail("planar_voxel_m", "finite and >= 0", planar_voxel_m);
  if (!(less_flat_voxel_m >= 0.0) || !std::isfinite(less_flat_voxel_m))
    return fail("less_flat_voxel_m", "finite and >= 0", less_flat_voxel_m);
  if (!(range_sigma_m >= 0.0) || !std::isfinite(range_sigma_m))
    return fail("range_sigma_m", "finite and >= 0", range_sigma_m);
  if (!(edge_min_snr >= 0.0) || !std::isfinite(edge_min_snr))
    return fail("edge_min_snr", "finite and >= 0", edge_min_snr);
  if (!(range_sigma_incidence_exponent >= 0.0) || !(range_sigma_incidence_exponent <= 10.0))
    return fail("range_sigma_incidence_exponent", "in [0, 10]", range_sigma_incidence_exponent);
  if (!(range_sigma_min_cos > 0.0) || !(range_sigma_min_cos <= 1.0))
    return fail("range_sigma_min_cos", "in (0, 1]", range_sigma_min_cos);
  if (threads < 0) return fail("threads", ">= 0", threads);
  return true;
}

std::vector<float> RingCurvature(const std::vector<ScanPoint>& ring, int neighbours, double max_step_deg) {
  ROTOLIDAR_CHECK(neighbours >= 1, "neighbours = " << neighbours);
  Ring r;
  for (std::size_t i = 0; i < ring.size(); ++i) r.index.push_back(static_cast<int>(i));
  GatherRing(ring, &r);
  return CurvatureOf(r.x, r.y, r.z, r.range, StepsOk(r.az, max_step_deg), neighbours);
}

FeatureResult ExtractFeatures(const std::vector<ScanPoint>& points, Seconds t_scan_start_s,
                              const FeatureConfig& config) {
  std::string why;
  ROTOLIDAR_CHECK(config.Validate(&why), why);
  const double n_side = config.neighbours;
  Context ctx{points, config, {}, std::vector<FeatureLabel>(points.size(), FeatureLabel::kInvalid),
              std::tan(config.beam_parallel_max_incidence_deg * kDegToRad),
              config.range_sigma_m * std::sqrt(4.0 * n_side * n_side + 2.0 * n_side)};
  std::vector<uint8_t> valid(points.size(), 0);
  std::vector<int> per_ring;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const ScanPoint& p = points[i];
    valid[i] = p.p_base.allFinite() && p.range_m > 0.f && std::isfinite(p.range_m) && std::isfinite(p.azimuth_deg);
    if (!valid[i]) continue;
    if (p.ring >= per_ring.size()) per_ring.resize(p.ring + 1u, 0);
    ++per_ring[p.ring];
  }
  ctx.rings.resize(per_ring.size());
  for (std::size_t r = 0; r < per_ring.size(); ++r) ctx.rings[r].index.reserve(per_ring[r]);
  for (std::size_t i = 0; i < points.size(); ++i)
    if (valid[i]) ctx.rings[points[i].ring].index.push_back(static_cast<int>(i));
  const int threads =
      config.threads > 0 ? config.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  const int n_rings = static_cast<int>(ctx.rings.size());
  ParallelFor(n_rings, threads, [&](int r) { AnalyseRing(&ctx, &ctx.rings[r]); });
  std::vector<SectorOutput> sectors(config.sectors);
  ParallelFor(config.sectors, threads, [&](int s) {
    CellScratch scratch;
    for (int r = 0; r < n_rings; ++r) SelectCell(&ctx, s, &ctx.rings[r], &sectors[s], &scratch);
  });

  FeatureResult result;
  result.features.t_s = t_scan_start_s;
  std::vector<int> less_flat_raw;
  for (const SectorOutput& s : sectors) {  // sector order, then ring order inside: thread-count independent
    result.features.edge += s.edge;
    result.features.planar += s.planar;
    result.features.less_sharp += s.less_sharp;
    less_flat_raw.insert(less_flat_raw.end(), s.less_flat.begin(), s.less_flat.end());
  }
  result.curvature.assign(points.size(), kNaN);
  for (const Ring& ring : ctx.rings)
    for (std::size_t i = 0; i < ring.index.size(); ++i) result.curvature[ring.index[i]] = ring.c[i];
  result.features.less_flat = LessFlatCloud(ctx, less_flat_raw, result.curvature, config.less_flat_voxel_m);
  if (config.planar_voxel_m > 0.0)
    result.features.planar = VoxelDownsampled(result.features.planar, config.planar_voxel_m);
  result.stats = CountLabels(ctx.labels, result.features, less_flat_raw.size());
  result.labels = std::move(ctx.labels);
  return result;
}

}  // namespace rotolidar
