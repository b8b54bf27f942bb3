#include "bench/eval/alignment.hpp"

#include <cmath>

#include <Eigen/SVD>

namespace rotolidar::bench {
namespace {

constexpr double kRankRelTol = 1e-12;

AlignmentResult Fail(std::string msg) {
  AlignmentResult r;
  r.success = false;
  r.message = std::move(msg);
  return r;
}

Eigen::Vector3d Mean(const std::vector<Eigen::Vector3d>& p) {
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (const auto& x : p) m += x;
  return m / static_cast<double>(p.size());
}

// Umeyama (1991), written as evo's umeyama_alignment (x = estimate, y = reference) so that results agree to
// rounding: Sigma_xy = 1/n sum (y - mu_y)(x - mu_x)^T = U D V^T; R = U S V^T with S fixing a reflection;
// c = trace(D S) / sigma_x^2; t = mu_y - c R mu_x.
AlignmentResult Umeyama(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y,
                        bool with_scale) {
  if (x.size() < 3) return Fail("Umeyama alignment needs at least 3 associated poses, got " +
                                std::to_string(x.size()));
  const double n = static_cast<double>(x.size());
  const Eigen::Vector3d mu_x = Mean(x), mu_y = Mean(y);
  double sigma_x = 0.0;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < x.size(); ++i) {
    sigma_x += (x[i] - mu_x).squaredNorm();
    cov += (y[i] - mu_y) * (x[i] - mu_x).transpose();
  }
  sigma_x /= n;
  cov /= n;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d d = svd.singularValues();  // descending
  if (!(d(0) > 0.0) || d(1) <= kRankRelTol * d(0)) {
    return Fail("degenerate covariance rank (positions collinear or identical): Umeyama alignment is not possible");
  }
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;
  AlignmentResult r;
  r.success = true;
  const Eigen::Matrix3d R = svd.matrixU() * S * svd.matrixV().transpose();
  r.scale = with_scale ? (d.asDiagonal() * S).trace() / sigma_x : 1.0;
  r.T_ref_est.linear() = R;
  r.T_ref_est.translation() = mu_y - r.scale * R * mu_x;
  return r;
}

// 4-DOF: maximise sum y'^T Rz(theta) x' over centred points; only the x/y components depend on theta:
// theta = atan2(sum(x'_x y'_y - x'_y y'_x), sum(x'_x y'_x + x'_y y'_y)); t = mu_y - Rz mu_x.
AlignmentResult PosYaw(const std::vector<Eigen::Vector3d>& x, const std::vector<Eigen::Vector3d>& y) {
  if (x.size() < 2) return Fail("position+yaw alignment needs at least 2 associated poses, got " +
                                std::to_string(x.size()));
  const Eigen::Vector3d mu_x = Mean(x), mu_y = Mean(y);
  double s = 0.0, c = 0.0, spread = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector3d a = x[i] - mu_x, b = y[i] - mu_y;
    s += a.x() * b.y() - a.y() * b.x();
    c += a.x() * b.x() + a.y() * b.y();
    spread += a.head<2>().squaredNorm() + b.head<2>().squaredNorm();
  }
  if (!(std::hypot(s, c) > kRankRelTol * spread) || !(spread > 0.0)) {
    return Fail("degenerate input for position+yaw alignment: no horizontal spread or correlation");
  }
  AlignmentResult r;
  r.success = true;
  r.T_ref_est = RotZ(std::atan2(s, c));
  r.T_ref_est.translation() = mu_y - r.T_ref_est.linear() * mu_x;
  return r;
}

}  // namespace

bool ParseAlignment(const std::string& name, Alignment* out) {
  if (name == "none") *out = Alignment::kNone;
  else if (name == "se3") *out = Alignment::kSe3;
  else if (name == "sim3") *out = Alignment::kSim3;
  else if (name == "posyaw") *out = Alignment::kPosYaw;
  else return false;
  return true;
}

const char* AlignmentName(Alignment alignment) {
  switch (alignment) {
    case Alignment::kNone: return "none";
    case Alignment::kSe3: return "se3";
    case Alignment::kSim3: return "sim3";
    case Alignment::kPosYaw: return "posyaw";
  }
  return "?";
}

AlignmentResult AlignPositions(const std::vector<Eigen::Vector3d>& p_est, const std::vector<Eigen::Vector3d>& p_ref,
                               Alignment alignment) {
  if (p_est.size() != p_ref.size()) {
    return Fail("alignment needs equally many estimate and reference positions (" + std::to_string(p_est.size()) +
                " vs " + std::to_string(p_ref.size()) + ")");
  }
  switch (alignment) {
    case Alignment::kNone: {
      AlignmentResult r;
      r.success = true;
      return r;
    }
    case Alignment::kSe3: return Umeyama(p_est, p_ref, false);
    case Alignment::kSim3: return Umeyama(p_est, p_ref, true);
    case Alignment::kPosYaw: return PosYaw(p_est, p_ref);
  }
  return Fail("unknown alignment");
}

std::vector<Eigen::Vector3d> Positions(const Trajectory& traj) {
  std::vector<Eigen::Vector3d> p;
  p.reserve(traj.size());
  for (const auto& sp : traj) p.push_back(sp.T_ref_body.translation());
  return p;
}

Trajectory ApplyAlignment(const AlignmentResult& alignment, const Trajectory& traj) {
  Trajectory out = traj;
  const Eigen::Matrix3d& R = alignment.T_ref_est.linear();
  for (auto& sp : out) {
    sp.T_ref_body.translation() = alignment.scale * R * sp.T_ref_body.translation() +
                                  alignment.T_ref_est.translation();
    sp.T_ref_body.linear() = R * sp.T_ref_body.linear();
  }
  return out;
}

}  // namespace rotolidar::bench
