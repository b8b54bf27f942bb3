#include "bench/metrics/geometry_accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Dense>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "bench/metrics/coverage.hpp"

namespace rotolidar::bench {
namespace {

// Map points in the element frame E with their surface normals (unit; zero where too few neighbours).
struct Points {
  std::vector<Eigen::Vector3d> p;
  std::vector<Eigen::Vector3d> n;
};

// PCA normals: the smallest-eigenvalue axis of the neighbours within radius_m, or of the kMinNeighbours
// nearest when the radius holds fewer.
constexpr int kMinNeighbours = 10;
void EstimateNormals(double radius_m, Points* pts) {
  pts->n.assign(pts->p.size(), Eigen::Vector3d::Zero());
  if (pts->p.empty()) return;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (const Eigen::Vector3d& q : pts->p) cloud->push_back(pcl::PointXYZ(q.x(), q.y(), q.z()));
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  std::vector<int> idx;
  std::vector<float> sq;
  for (size_t i = 0; i < pts->p.size(); ++i) {
    // Sparse maps: fall back to the nearest kMinNeighbours when the radius holds fewer.
    if (tree.radiusSearch(cloud->points[i], radius_m, idx, sq) < kMinNeighbours &&
        tree.nearestKSearch(cloud->points[i], kMinNeighbours, idx, sq) < kMinNeighbours)
      continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int k : idx) mean += pts->p[static_cast<size_t>(k)];
    mean /= static_cast<double>(idx.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int k : idx) {
      const Eigen::Vector3d d = pts->p[static_cast<size_t>(k)] - mean;
      cov += d * d.transpose();
    }
    pts->n[i] = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  }
}

// Coordinate `axis` of the points inside the box [lo, hi] (element frame) whose normal lies within the
// configured angle of that axis (a plane perpendicular to it).
std::vector<double> Coordinates(const Points& pts, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int axis,
                                double min_cos) {
  std::vector<double> out;
  for (size_t i = 0; i < pts.p.size(); ++i) {
    const Eigen::Vector3d& p = pts.p[i];
    if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all() && std::abs(pts.n[i][axis]) >= min_cos)
      out.push_back(p[axis]);
  }
  return out;
}

// Circle through xy: an algebraic (Kasa) start, then Gauss-Newton on the geometric distances (the Kasa fit
// alone shrinks the radius on a partial, noisy arc); trimmed: points farther than 3 robust sigmas (min 1 cm)
// are dropped and the fit repeated. False with fewer than min_points inliers.
bool FitCircle(std::vector<Eigen::Vector2d> xy, int min_points, double* radius) {
  for (int round = 0; round < 4; ++round) {
    if (static_cast<int>(xy.size()) < min_points) return false;
    Eigen::MatrixXd A(xy.size(), 3);
    Eigen::VectorXd b(xy.size());
    for (size_t i = 0; i < xy.size(); ++i) {
      A.row(i) << 2 * xy[i].x(), 2 * xy[i].y(), 1.0;
      b(i) = xy[i].squaredNorm();
    }
    const Eigen::Vector3d k = A.colPivHouseholderQr().solve(b);
    Eigen::Vector3d x(k(0), k(1), std::sqrt(std::max(0.0, k(2) + k.head<2>().squaredNorm())));  // cx, cy, r
    for (int it = 0; it < 10; ++it) {
      Eigen::MatrixXd J(xy.size(), 3);
      Eigen::VectorXd res(xy.size());
      for (size_t i = 0; i < xy.size(); ++i) {
        const Eigen::Vector2d d = xy[i] - x.head<2>();
        const double dn = std::max(d.norm(), 1e-9);
        res(i) = dn - x(2);
        J.row(i) << -d.x() / dn, -d.y() / dn, -1.0;
      }
      x -= J.colPivHouseholderQr().solve(res);
    }
    *radius = x(2);
    std::vector<double> abs_res;
    for (const Eigen::Vector2d& p : xy) abs_res.push_back(std::abs((p - x.head<2>()).norm() - x(2)));
    const double limit = std::max(0.01, 3.0 * 1.4826 * Quantile(abs_res, 0.5));
    std::vector<Eigen::Vector2d> kept;
    for (size_t i = 0; i < xy.size(); ++i)
      if (abs_res[i] <= limit) kept.push_back(xy[i]);
    if (kept.size() == xy.size()) return true;
    xy.swap(kept);
  }
  return static_cast<int>(xy.size()) >= min_points;
}

void SetWidth(double value, ElementMeasurement* m) {
  m->width_measured = true;
  m->width_m = value;
  m->width_error_m = value - m->true_width_m;
}

void SetHeight(double value, ElementMeasurement* m) {
  m->height_measured = true;
  m->height_m = value;
  m->height_error_m = value - m->true_height_m;
}

// The plane perpendicular to `axis` from the points in the box [lo, hi] with a normal along `axis`, searched
// over [lo[axis], hi[axis]].
// The clutter level comes from every point in the box, whatever its normal: a surface blurred into a slab
// (a drifting map's double wall) has no plane to find.
bool Plane(const Points& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int axis, const ElementFitConfig& c,
           double* offset) {
  const std::vector<double> all = Coordinates(p, lo, hi, axis, 0.0);
  return PlaneOffsetByMode(Coordinates(p, lo, hi, axis, c.normal_min_cos), lo[axis], hi[axis], c, offset, &all);
}

// Door or window: jambs (planes y = +-w/2) and sill/floor + lintel (planes z = -+h/2) inside the wall thickness.
void MeasureOpening(const Points& p, double depth_m, const ElementFitConfig& c, ElementMeasurement* m) {
  const double w2 = 0.5 * m->true_width_m, h2 = 0.5 * m->true_height_m, s = c.search_margin_m;
  // The central part of the reveal, in all three directions: away from the wall faces, corners and edges.
  const double bx = c.band_fraction * 0.5 * depth_m, bz = c.band_fraction * h2, by = c.band_fraction * w2;
  double left = 0, right = 0, bottom = 0, top = 0;
  // Each plane is searched within +-s of its annotated place (not past the centre).
  const double iw = std::max(w2 - s, 0.0), ih = std::max(h2 - s, 0.0);
  const bool l = Plane(p, {-bx, -w2 - s, -bz}, {bx, -iw, bz}, 1, c, &left);
  const bool r = Plane(p, {-bx, iw, -bz}, {bx, w2 + s, bz}, 1, c, &right);
  const bool b = Plane(p, {-bx, -by, -h2 - s}, {bx, by, -ih}, 2, c, &bottom);
  const bool t = Plane(p, {-bx, -by, ih}, {bx, by, h2 + s}, 2, c, &top);
  if (l && r) SetWidth(right - left, m);
  if (b && t) SetHeight(top - bottom, m);
  std::ostringstream why;
  if (!l) why << "no left jamb; ";
  if (!r) why << "no right jamb; ";
  if (!b) why << (m->type == "door" ? "no floor; " : "no sill; ");
  if (!t) why << "no lintel; ";
  m->message = why.str();
}

// Column: width across (circle or the faces y = +-w/2), height from the floor and ceiling around it.
void MeasureColumn(const Points& p, bool round, double depth_m, const ElementFitConfig& c, ElementMeasurement* m) {
  const double w2 = 0.5 * m->true_width_m, d2 = 0.5 * depth_m, h2 = 0.5 * m->true_height_m, s = c.search_margin_m;
  const double bz = c.band_fraction * h2;
  std::ostringstream why;
  if (round) {
    std::vector<Eigen::Vector2d> xy;
    for (size_t i = 0; i < p.p.size(); ++i)
      if (std::abs(p.p[i].z()) <= bz && std::abs(p.n[i].z()) <= std::sqrt(1.0 - c.normal_min_cos * c.normal_min_cos)) xy.push_back(p.p[i].head<2>());
    double radius = 0;
    if (FitCircle(xy, c.min_points, &radius)) SetWidth(2 * radius, m);
    else why << "too few points on the column; ";
  } else {
    const double bx = c.band_fraction * d2;
    double left = 0, right = 0;
    const double iw = std::max(w2 - s, 0.0);
    const bool l = Plane(p, {-bx, -w2 - s, -bz}, {bx, -iw, bz}, 1, c, &left);
    const bool r = Plane(p, {-bx, iw, -bz}, {bx, w2 + s, bz}, 1, c, &right);
    if (l && r) SetWidth(right - left, m);
    else why << "no column faces; ";
  }
  // Floor and ceiling in a ring around the column (outside it by 5 cm, within the search margin).
  Points ring;
  for (size_t i = 0; i < p.p.size(); ++i) {
    const double out = std::max(std::abs(p.p[i].x()) - d2, std::abs(p.p[i].y()) - w2);
    if (out >= 0.05 && out <= s) ring.p.push_back(p.p[i]), ring.n.push_back(p.n[i]);
  }
  const Eigen::Vector3d far(d2 + s, w2 + s, 0);
  double bottom = 0, top = 0;
  const bool b = Plane(ring, -far - Eigen::Vector3d(0, 0, h2 + s), far - Eigen::Vector3d(0, 0, h2 - s), 2, c, &bottom);
  const bool t = Plane(ring, -far + Eigen::Vector3d(0, 0, h2 - s), far + Eigen::Vector3d(0, 0, h2 + s), 2, c, &top);
  if (b && t) SetHeight(top - bottom, m);
  if (!b) why << "no floor; ";
  if (!t) why << "no ceiling; ";
  m->message = why.str();
}

}  // namespace

bool ElementFitConfig::Validate(std::string* error) const {
  auto fail = [&](const char* what) { return (*error = std::string("element fit: ") + what), false; };
  if (!(search_margin_m > 0)) return fail("search_margin_m must be > 0");
  if (!(default_depth_m > 0)) return fail("default_depth_m must be > 0");
  if (!(band_fraction > 0 && band_fraction <= 1)) return fail("band_fraction must be in (0, 1]");
  if (!(bin_m > 0)) return fail("bin_m must be > 0");
  if (!(refine_halfwidth_m >= bin_m)) return fail("refine_halfwidth_m must be >= bin_m");
  if (min_points < 3) return fail("min_points must be >= 3");
  if (!(normal_radius_m > 0)) return fail("normal_radius_m must be > 0");
  if (!(normal_min_cos >= 0 && normal_min_cos <= 1)) return fail("normal_min_cos must be in [0, 1]");
  if (!(prominence >= 0)) return fail("prominence must be >= 0");
  return true;
}

namespace {
std::vector<double> Histogram(const std::vector<double>& values, double lo, int bins, double bin_m) {
  std::vector<double> count(static_cast<size_t>(bins), 0.0);
  for (double v : values) {
    if (v < lo || v > lo + bins * bin_m) continue;
    const int i = std::min(bins - 1, static_cast<int>((v - lo) / bin_m));
    count[static_cast<size_t>(i)] += 1.0;
  }
  return count;
}
}  // namespace

bool PlaneOffsetByMode(const std::vector<double>& values, double lo, double hi, const ElementFitConfig& config,
                       double* offset, const std::vector<double>* clutter_values) {
  if (!(hi > lo) || values.empty()) return false;
  const int bins = std::max(1, static_cast<int>(std::ceil((hi - lo) / config.bin_m)));
  const std::vector<double> count = Histogram(values, lo, bins, config.bin_m);
  int best = -1;
  double best_count = 0.0;
  for (int i = 0; i < bins; ++i) {  // 3-bin smoothing; the first maximum wins (deterministic)
    const double c = count[i] + (i > 0 ? count[i - 1] : 0.0) + (i + 1 < bins ? count[i + 1] : 0.0);
    if (c > best_count) best_count = c, best = i;
  }
  if (best < 0) return false;
  const double mode = lo + (best + 0.5) * config.bin_m;
  std::vector<double> near;
  for (double v : values)
    if (std::abs(v - mode) <= config.refine_halfwidth_m) near.push_back(v);
  // Prominence: the peak must stand out of the clutter level (the median bin count) over its window.
  const double level = Quantile(clutter_values ? Histogram(*clutter_values, lo, bins, config.bin_m) : count, 0.5);
  const double clutter = level * (2.0 * config.refine_halfwidth_m / config.bin_m);
  const double needed = std::max(static_cast<double>(config.min_points), config.prominence * clutter);
  if (static_cast<double>(near.size()) < needed) return false;
  *offset = Quantile(near, 0.5);
  return true;
}

ElementMeasurement MeasureElement(const sim::Scene& scene, const sim::AnnotatedElement& element,
                                  const std::vector<Eigen::Vector3f>& map_world, const ElementFitConfig& config) {
  ElementMeasurement m;
  m.name = element.name;
  m.type = element.type;
  m.true_width_m = element.width_m;
  m.true_height_m = element.height_m;
  const bool column = element.type == "column";
  const double depth = element.depth_m > 0 ? element.depth_m : (column ? element.width_m : config.default_depth_m);
  // Crop: the element's box grown by the search margin, in E.
  const Eigen::Isometry3d T_element_world = element.T_world_element().inverse();
  const Eigen::Vector3d half =
      0.5 * Eigen::Vector3d(depth, element.width_m, element.height_m) + Eigen::Vector3d::Constant(config.search_margin_m);
  Points p_element;
  for (const Eigen::Vector3f& p : map_world) {
    const Eigen::Vector3d q = T_element_world * p.cast<double>();
    if ((q.cwiseAbs().array() <= half.array()).all()) p_element.p.push_back(q);
  }
  m.crop_points = p_element.p.size();
  EstimateNormals(config.normal_radius_m, &p_element);
  if (column) {
    bool round = false;
    for (const sim::Primitive& prim : scene.primitives)
      if (!element.primitive.empty() && prim.name == element.primitive) round = prim.type == sim::PrimitiveType::kCylinder;
    MeasureColumn(p_element, round, depth, config, &m);
  } else {
    MeasureOpening(p_element, depth, config, &m);
  }
  return m;
}

ElementSummary SummarizeElements(const std::vector<ElementMeasurement>& elements) {
  ElementSummary s;
  s.elements = elements.size();
  double sw = 0, sh = 0;
  for (const ElementMeasurement& m : elements) {
    if (m.width_measured) ++s.widths_measured, sw += m.width_error_m * m.width_error_m,
                          s.max_abs_error_m = std::max(s.max_abs_error_m, std::abs(m.width_error_m));
    if (m.height_measured) ++s.heights_measured, sh += m.height_error_m * m.height_error_m,
                           s.max_abs_error_m = std::max(s.max_abs_error_m, std::abs(m.height_error_m));
  }
  if (s.widths_measured) s.width_rmse_m = std::sqrt(sw / static_cast<double>(s.widths_measured));
  if (s.heights_measured) s.height_rmse_m = std::sqrt(sh / static_cast<double>(s.heights_measured));
  const size_t n = s.widths_measured + s.heights_measured;
  if (n) s.rmse_m = std::sqrt((sw + sh) / static_cast<double>(n));
  return s;
}

}  // namespace rotolidar::bench
