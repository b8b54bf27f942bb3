// Plane residuals of VLP-16 revolutions (contract in plane_residuals.hpp).
#include "bench/eval/plane_residuals.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <Eigen/Eigenvalues>
#include <pcl/ModelCoefficients.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"
#include "core/wire/pcap.hpp"
#include "core/wire/scan_splitter.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench {
namespace {

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

bool Increasing(const std::vector<double>& v) {
  if (v.size() < 2) return false;
  for (std::size_t i = 1; i < v.size(); ++i)
    if (!(v[i] > v[i - 1])) return false;
  return true;
}

/// Least-squares plane (unit normal n, offset d: n . p + d = 0) through the points, n turned towards the origin.
void FitPlane(const std::vector<Eigen::Vector3d>& pts, Eigen::Vector3d* n, double* d) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  *n = eig.eigenvectors().col(0);  // smallest eigenvalue
  *d = -n->dot(mean);
  if (*d < 0.0) {  // the origin (sensor) on the positive side
    *n = -*n;
    *d = -*d;
  }
}

double Quantile(std::vector<double>* v, double q) {
  if (v->empty()) return 0.0;
  const std::size_t k = std::min(v->size() - 1, static_cast<std::size_t>(q * static_cast<double>(v->size())));
  std::nth_element(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(k), v->end());
  return (*v)[k];
}

ResidualBin Stats(const std::vector<double>& signed_m, double lo, double hi) {
  ResidualBin b;
  b.lo = lo, b.hi = hi, b.count = signed_m.size();
  if (signed_m.empty()) return b;
  std::vector<double> abs_m(signed_m.size());
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < signed_m.size(); ++i) {
    abs_m[i] = std::abs(signed_m[i]);
    sum += signed_m[i];
    sum2 += signed_m[i] * signed_m[i];
  }
  b.median_abs_m = Quantile(&abs_m, 0.5);
  b.p90_abs_m = Quantile(&abs_m, 0.9);
  const double n = static_cast<double>(signed_m.size());
  b.std_m = std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
  return b;
}

/// Planes of one revolution, appended to *result.
void ScanPlanes(const LidarScan& scan, int scan_index, const PlaneResidualOptions& o, PlaneResidualResult* result) {
  std::vector<Eigen::Vector3d> pts;
  std::vector<float> intensity;
  for (const LidarPoint& p : scan.points) {
    const Eigen::Vector3d v(p.x_m, p.y_m, p.z_m);
    const double r = v.norm();
    if (r < o.min_range_m || r > o.max_range_m) continue;
    pts.push_back(v);
    intensity.push_back(p.intensity);
  }
  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setOptimizeCoefficients(false);
  seg.setModelType(pcl::SACMODEL_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setDistanceThreshold(o.ransac_threshold_m);
  seg.setMaxIterations(o.ransac_iterations);
  for (int plane = 0; plane < o.max_planes && static_cast<int>(pts.size()) >= o.min_plane_points; ++plane) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    cloud->reserve(pts.size());
    for (const auto& p : pts) cloud->push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                                             static_cast<float>(p.z())));
    seg.setInputCloud(cloud);
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coefficients;
    seg.segment(inliers, coefficients);
    if (static_cast<int>(inliers.indices.size()) < o.min_plane_points) break;
    std::vector<Eigen::Vector3d> in;
    for (int i : inliers.indices) in.push_back(pts[static_cast<std::size_t>(i)]);
    Eigen::Vector3d n;
    double d = 0.0;
    FitPlane(in, &n, &d);
    const bool measured = d >= o.min_plane_offset_m;
    std::vector<Eigen::Vector3d> rest;
    std::vector<float> rest_intensity;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double dist = n.dot(pts[i]) + d;
      if (std::abs(dist) > o.ransac_threshold_m) {
        rest.push_back(pts[i]);
        rest_intensity.push_back(intensity[i]);
        continue;
      }
      if (!measured) continue;
      const double r = pts[i].norm();
      PlaneResidual pr;
      pr.range_m = static_cast<float>(r);
      pr.incidence_deg = static_cast<float>(std::acos(std::min(1.0, std::abs(n.dot(pts[i])) / r)) * kDegPerRad);
      pr.residual_m = static_cast<float>(dist);
      pr.intensity = intensity[i];
      pr.scan = scan_index;
      pr.plane = plane;
      result->points.push_back(pr);
    }
    result->planes += measured ? 1 : 0;
    pts.swap(rest);
    intensity.swap(rest_intensity);
  }
}

}  // namespace

bool PlaneResidualOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) { return (error ? *error = m : m), false; };
  if (!(min_range_m >= 0.0 && max_range_m > min_range_m)) return fail("plane residuals: need 0 <= min_range < max_range");
  if (!(ransac_threshold_m > 0.0 && ransac_threshold_m < 1.0)) return fail("plane residuals: threshold in (0, 1) m");
  if (!(min_plane_offset_m >= 0.0)) return fail("plane residuals: min_plane_offset_m >= 0");
  if (max_planes < 1 || min_plane_points < 3 || ransac_iterations < 1) {
    return fail("plane residuals: max_planes >= 1, min_plane_points >= 3, ransac_iterations >= 1");
  }
  if (!Increasing(range_edges_m) || !Increasing(incidence_edges_deg)) {
    return fail("plane residuals: bin edges must be >= 2 increasing values");
  }
  return true;
}

Status RevolutionsFromPackets(const std::vector<LidarPacket>& packets, const LidarIntrinsics& intrinsics,
                              std::vector<LidarScan>* scans) {
  Vlp16Decoder decoder(intrinsics, Vlp16DecoderConfig{});
  RevolutionSplitter splitter(0.0);
  std::vector<LidarPoint> points;
  std::vector<LidarScan> pieces;
  for (const LidarPacket& packet : packets) {
    points.clear();
    if (Status s = decoder.Decode(packet, &points); !s) return s;
    splitter.Add(points, &pieces);
  }
  scans->clear();
  // The first piece starts anywhere; the trailing one (never flushed) is partial too.
  for (std::size_t i = 1; i < pieces.size(); ++i) scans->push_back(std::move(pieces[i]));
  if (scans->empty()) return Status::Error("no full revolution in " + std::to_string(packets.size()) + " packets");
  return Status::Ok();
}

Status LoadLidarRevolutions(const std::string& input, std::vector<LidarScan>* scans) {
  std::vector<LidarPacket> packets;
  LidarIntrinsics intrinsics;
  std::string pcap = input;
  if (std::filesystem::is_directory(input)) {
    RigCalib calib;
    if (Status s = LoadCalibYaml(input + "/" + RecordingLayout::kCalib, &calib); !s) return s;
    intrinsics = calib.lidar;
    pcap = input + "/" + RecordingLayout::kLidar;
  } else if (input.size() >= 4 && input.compare(input.size() - 4, 4, ".bin") == 0) {
    if (Status s = ReadRawVlp16Payloads(input, &packets); !s) return s;
    pcap.clear();
  }
  if (!pcap.empty()) {
    PcapReader reader;
    if (Status s = reader.Open(pcap); !s) return s;
    LidarPacket packet;
    Status status;
    while (reader.Next(&packet, &status)) packets.push_back(packet);
    if (!status) return status;
  }
  if (Status s = RevolutionsFromPackets(packets, intrinsics, scans); !s) return Status::Error(input + ": " + s.message);
  return Status::Ok();
}

std::vector<ResidualBin> BinResiduals(const std::vector<PlaneResidual>& points, const std::vector<double>& edges,
                                      bool by_incidence) {
  std::vector<std::vector<double>> values(edges.size() - 1);
  for (const PlaneResidual& p : points) {
    const double key = by_incidence ? p.incidence_deg : p.range_m;
    const auto it = std::upper_bound(edges.begin(), edges.end(), key);
    if (it == edges.begin() || it == edges.end()) continue;
    values[static_cast<std::size_t>(it - edges.begin() - 1)].push_back(p.residual_m);
  }
  std::vector<ResidualBin> bins;
  for (std::size_t i = 0; i + 1 < edges.size(); ++i) bins.push_back(Stats(values[i], edges[i], edges[i + 1]));
  return bins;
}

Status MeasurePlaneResiduals(const std::vector<LidarScan>& scans, const PlaneResidualOptions& options,
                             PlaneResidualResult* result) {
  if (std::string why; !options.Validate(&why)) return Status::Error(why);
  *result = PlaneResidualResult();
  for (std::size_t s = 0; s < scans.size(); ++s) ScanPlanes(scans[s], static_cast<int>(s), options, result);
  result->scans = static_cast<int>(scans.size());
  if (result->points.empty()) return Status::Error("plane residuals: no plane found in " + std::to_string(scans.size()) +
                                                   " revolutions");
  result->by_range = BinResiduals(result->points, options.range_edges_m, false);
  result->by_incidence = BinResiduals(result->points, options.incidence_edges_deg, true);
  std::vector<double> all;
  for (const PlaneResidual& p : result->points) all.push_back(p.residual_m);
  result->all = Stats(all, options.range_edges_m.front(), options.range_edges_m.back());
  return Status::Ok();
}

Status WritePlaneResidualCsv(const std::string& path, const PlaneResidualResult& result) {
  std::ofstream out(path);
  if (!out) return Status::Error(path + ": cannot create");
  out << "range_m,incidence_deg,residual_m,intensity,scan,plane\n";
  char line[128];
  for (const PlaneResidual& p : result.points) {
    const int n = std::snprintf(line, sizeof(line), "%.4f,%.2f,%.5f,%.0f,%d,%d\n", p.range_m, p.incidence_deg,
                                p.residual_m, p.intensity, p.scan, p.plane);
    out.write(line, n);
  }
  return out ? Status::Ok() : Status::Error(path + ": write error");
}

void PrintPlaneResiduals(const PlaneResidualResult& result, std::ostream& os) {
  char line[160];
  std::snprintf(line, sizeof(line), "revolutions %d, planes %d, points %zu: |residual| median %.1f mm, p90 %.1f mm, "
                "std %.1f mm\n", result.scans, result.planes, result.points.size(), 1e3 * result.all.median_abs_m,
                1e3 * result.all.p90_abs_m, 1e3 * result.all.std_m);
  os << line;
  auto table = [&](const char* what, const std::vector<ResidualBin>& bins) {
    os << what << "        points   median_mm   p90_mm   std_mm\n";
    for (const ResidualBin& b : bins) {
      if (b.count == 0) continue;
      std::snprintf(line, sizeof(line), "%6.1f - %-6.1f %8zu %10.1f %8.1f %8.1f\n", b.lo, b.hi, b.count,
                    1e3 * b.median_abs_m, 1e3 * b.p90_abs_m, 1e3 * b.std_m);
      os << line;
    }
  };
  table("range [m]    ", result.by_range);
  table("incidence [deg]", result.by_incidence);
}

}  // namespace rotolidar::bench
