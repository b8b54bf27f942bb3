#include "bench/metrics/geometry_accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Dense>

#include "bench/metrics/coverage.hpp"

namespace rotolidar::bench {
namespace {

using Points = std::vector<Eigen::Vector3d>;  // element frame E

// Coordinate `axis` of the points inside the box [lo, hi] (element frame).
std::vector<double> Coordinates(const Points& points, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int axis) {
  std::vector<double> out;
  for (const Eigen::Vector3d& p : points)
    if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()) out.push_back(p[axis]);
  return out;
}

// Least-squares circle (Kasa) through xy, trimmed: points farther than 3 robust sigmas (min 1 cm) from the
// circle are dropped and the fit repeated. False with fewer than min_points inliers.
bool FitCircle(std::vector<Eigen::Vector2d> xy, int min_points, double* radius) {
  for (int iteration = 0; iteration < 4; ++iteration) {
    if (static_cast<int>(xy.size()) < min_points) return false;
    Eigen::MatrixXd A(xy.size(), 3);
    Eigen::VectorXd b(xy.size());
    for (size_t i = 0; i < xy.size(); ++i) {
      A.row(i) << 2 * xy[i].x(), 2 * xy[i].y(), 1.0;
      b(i) = xy[i].squaredNorm();
    }
    const Eigen::Vector3d s = A.colPivHouseholderQr().solve(b);
    const Eigen::Vector2d c = s.head<2>();
    *radius = std::sqrt(std::max(0.0, s(2) + c.squaredNorm()));
    std::vector<double> abs_res;
    for (const Eigen::Vector2d& p : xy) abs_res.push_back(std::abs((p - c).norm() - *radius));
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

// Door or window: jambs (planes y = +-w/2) and sill/floor + lintel (planes z = -+h/2) inside the wall thickness.
void MeasureOpening(const Points& p, double depth_m, const ElementFitConfig& c, ElementMeasurement* m) {
  const double w2 = 0.5 * m->true_width_m, h2 = 0.5 * m->true_height_m, s = c.search_margin_m;
  const double bx = std::max(0.5 * depth_m - c.face_margin_m, 0.01);  // reveal band |x| <= bx
  const double bz = c.band_fraction * h2, by = c.band_fraction * w2;
  double left = 0, right = 0, bottom = 0, top = 0;
  const bool l = PlaneOffsetByMode(Coordinates(p, {-bx, -w2 - s, -bz}, {bx, 0, bz}, 1), -w2 - s, 0, c, &left);
  const bool r = PlaneOffsetByMode(Coordinates(p, {-bx, 0, -bz}, {bx, w2 + s, bz}, 1), 0, w2 + s, c, &right);
  const bool b = PlaneOffsetByMode(Coordinates(p, {-bx, -by, -h2 - s}, {bx, by, 0}, 2), -h2 - s, 0, c, &bottom);
  const bool t = PlaneOffsetByMode(Coordinates(p, {-bx, -by, 0}, {bx, by, h2 + s}, 2), 0, h2 + s, c, &top);
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
    for (const Eigen::Vector3d& q : p)
      if (std::abs(q.z()) <= bz && std::abs(q.x()) <= d2 + s && std::abs(q.y()) <= w2 + s) xy.emplace_back(q.x(), q.y());
    double radius = 0;
    if (FitCircle(xy, c.min_points, &radius)) SetWidth(2 * radius, m);
    else why << "too few points on the column; ";
  } else {
    const double bx = c.band_fraction * d2;
    double left = 0, right = 0;
    const bool l = PlaneOffsetByMode(Coordinates(p, {-bx, -w2 - s, -bz}, {bx, 0, bz}, 1), -w2 - s, 0, c, &left);
    const bool r = PlaneOffsetByMode(Coordinates(p, {-bx, 0, -bz}, {bx, w2 + s, bz}, 1), 0, w2 + s, c, &right);
    if (l && r) SetWidth(right - left, m);
    else why << "no column faces; ";
  }
  // Floor and ceiling in a ring around the column (outside it by 5 cm, within the search margin).
  std::vector<double> floor_z, ceiling_z;
  for (const Eigen::Vector3d& q : p) {
    const double ring = std::max(std::abs(q.x()) - d2, std::abs(q.y()) - w2);
    if (ring < 0.05 || ring > s) continue;
    if (std::abs(q.z() + h2) <= s) floor_z.push_back(q.z());
    if (std::abs(q.z() - h2) <= s) ceiling_z.push_back(q.z());
  }
  double bottom = 0, top = 0;
  const bool b = PlaneOffsetByMode(floor_z, -h2 - s, -h2 + s, c, &bottom);
  const bool t = PlaneOffsetByMode(ceiling_z, h2 - s, h2 + s, c, &top);
  if (b && t) SetHeight(top - bottom, m);
  if (!b) why << "no floor; ";
  if (!t) why << "no ceiling; ";
  m->message = why.str();
}

}  // namespace

bool ElementFitConfig::Validate(std::string* error) const {
  auto fail = [&](const char* what) { return (*error = std::string("element fit: ") + what), false; };
  if (!(search_margin_m > 0)) return fail("search_margin_m must be > 0");
  if (!(face_margin_m >= 0)) return fail("face_margin_m must be >= 0");
  if (!(default_depth_m > 0)) return fail("default_depth_m must be > 0");
  if (!(band_fraction > 0 && band_fraction <= 1)) return fail("band_fraction must be in (0, 1]");
  if (!(bin_m > 0)) return fail("bin_m must be > 0");
  if (!(refine_halfwidth_m >= bin_m)) return fail("refine_halfwidth_m must be >= bin_m");
  if (min_points < 3) return fail("min_points must be >= 3");
  return true;
}

bool PlaneOffsetByMode(const std::vector<double>& values, double lo, double hi, const ElementFitConfig& config,
                       double* offset) {
  if (!(hi > lo) || values.empty()) return false;
  const int bins = std::max(1, static_cast<int>(std::ceil((hi - lo) / config.bin_m)));
  std::vector<double> count(static_cast<size_t>(bins), 0.0);
  for (double v : values) {
    if (v < lo || v > hi) continue;
    const int i = std::min(bins - 1, static_cast<int>((v - lo) / config.bin_m));
    count[static_cast<size_t>(i)] += 1.0;
  }
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
  if (static_cast<int>(near.size()) < config.min_points) return false;
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
    if ((q.cwiseAbs().array() <= half.array()).all()) p_element.push_back(q);
  }
  m.crop_points = p_element.size();
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
