#include "core/backend/pose_factors.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/Geometry>

#include "core/backend/pose_jacobians.hpp"
#include "core/imu/pose_block_view.hpp"
#include "core/imu/preintegration.hpp"
#include "core/util/log.hpp"

namespace rotolidar {

namespace {

using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Quaterniond;
using Eigen::Vector3d;
using Eigen::VectorXd;
using RowMajorXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

using detail::LeftJacobianInverse;
using detail::PoseView;
using detail::QuaternionPlusJacobian;
using detail::ReadPose;
using detail::WriteAmbientPoseJacobian;

Matrix6d Symmetrize(const Matrix6d& M) { return 0.5 * (M + M.transpose()); }

}  // namespace

Matrix6d InformationFromRegistration(const Matrix6d& hessian, double point_sigma_m, const Matrix6d& projection) {
  ROTOLIDAR_CHECK(point_sigma_m > 0.0 && std::isfinite(point_sigma_m), "point_sigma_m must be > 0");
  return Symmetrize(projection.transpose() * hessian * projection / (point_sigma_m * point_sigma_m));
}

LidarPoseMeasurement LidarMeasurementInImuFrame(const Pose3& T_world_base, const Matrix6d& information_base,
                                                const Pose3& T_base_imu) {
  LidarPoseMeasurement m;
  m.T_world_imu = T_world_base * T_base_imu;
  // xi_imu = A xi_base with A = [I, -[a]x; 0, I], a = R_wb t_bi; A^-1 = [I, [a]x; 0, I].
  Matrix6d A_inv = Matrix6d::Identity();
  A_inv.block<3, 3>(0, 3) = so3::Hat(T_world_base.linear() * T_base_imu.translation());
  m.information = Symmetrize(A_inv.transpose() * information_base * A_inv);
  return m;
}

MatrixXd SqrtInformation(const MatrixXd& information) {
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(0.5 * (information + information.transpose()));
  const VectorXd sqrt_values = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return sqrt_values.asDiagonal() * eig.eigenvectors().transpose();
}

MatrixXd ToPoseTangentJacobian(const MatrixXd& J_ambient, const double* pose7) {
  ROTOLIDAR_CHECK(J_ambient.cols() == kImuPoseBlockSize, "a pose Jacobian has 7 columns");
  MatrixXd J(J_ambient.rows(), 6);
  J.leftCols<3>() = J_ambient.leftCols<3>();
  J.rightCols<3>() = 0.5 * J_ambient.rightCols<4>() * QuaternionPlusJacobian(ReadPose(pose7).q);
  return J;
}

// ---------------------------------------------------------------------------------------------- LidarPoseFactor

LidarPoseFactor::LidarPoseFactor(const LidarPoseMeasurement& measurement)
    : measurement_(measurement), sqrt_information_(SqrtInformation(measurement.information)) {}

Vector6d LidarPoseFactor::Error(const double* pose7) const {
  const PoseView x = ReadPose(pose7);
  Vector6d e;
  e.head<3>() = x.t - measurement_.T_world_imu.translation();
  e.tail<3>() = LogSO3(x.R * measurement_.T_world_imu.linear().transpose());
  return e;
}

bool LidarPoseFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Vector6d e = Error(parameters[0]);
  Eigen::Map<Vector6d>{residuals} = sqrt_information_ * e;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    // d e_t / d t = I;  d Log(Exp(phi) R R_m^T) / d phi = Jl^-1(e_R).
    WriteAmbientPoseJacobian(sqrt_information_.leftCols<3>(),
                             sqrt_information_.rightCols<3>() * LeftJacobianInverse(e.tail<3>()),
                             ReadPose(parameters[0]).q, jacobians[0]);
  }
  return true;
}

// ------------------------------------------------------------------------------------------- RelativePoseFactor

RelativePoseFactor::RelativePoseFactor(const Pose3& T_i_j_meas, const Matrix6d& information)
    : T_i_j_meas_(T_i_j_meas), sqrt_information_(SqrtInformation(information)) {}

Vector6d RelativePoseFactor::Error(const double* pose_i7, const double* pose_j7) const {
  const PoseView i = ReadPose(pose_i7), j = ReadPose(pose_j7);
  Vector6d e;
  e.head<3>() = i.R.transpose() * (j.t - i.t) - T_i_j_meas_.translation();
  e.tail<3>() = LogSO3(i.R.transpose() * j.R * T_i_j_meas_.linear().transpose());
  return e;
}

bool RelativePoseFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Vector6d e = Error(parameters[0], parameters[1]);
  Eigen::Map<Vector6d>{residuals} = sqrt_information_ * e;
  if (jacobians == nullptr) return true;
  const PoseView i = ReadPose(parameters[0]), j = ReadPose(parameters[1]);
  const Matrix3d RiT = i.R.transpose();
  const Matrix3d Jl_inv_RiT = LeftJacobianInverse(e.tail<3>()) * RiT;
  const Eigen::Matrix<double, 6, 3> S_t = sqrt_information_.leftCols<3>(), S_r = sqrt_information_.rightCols<3>();
  if (jacobians[0] != nullptr) {
    // R_i <- Exp(phi) R_i: e_t gains R_i^T [t_j - t_i]x phi, e_R gains -Jl^-1(e_R) R_i^T phi.
    WriteAmbientPoseJacobian(-S_t * RiT, S_t * RiT * so3::Hat(j.t - i.t) - S_r * Jl_inv_RiT, i.q, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    WriteAmbientPoseJacobian(S_t * RiT, S_r * Jl_inv_RiT, j.q, jacobians[1]);
  }
  return true;
}

// ------------------------------------------------------------------------------------- LinearizedPriorFactor

LinearizedPriorFactor::LinearizedPriorFactor(std::vector<BlockRef> blocks, std::vector<VectorXd> linearization_points,
                                             MatrixXd J, VectorXd r0)
    : blocks_(std::move(blocks)), x0_(std::move(linearization_points)), J_(std::move(J)), r0_(std::move(r0)) {
  ROTOLIDAR_CHECK(blocks_.size() == x0_.size(), "one linearisation point per block");
  int tangent = 0;
  for (size_t k = 0; k < blocks_.size(); ++k) {
    const BlockRef& b = blocks_[k];
    ROTOLIDAR_CHECK(b.values != nullptr && b.size > 0 && (b.kind == BlockKind::kVector || b.size == 7),
                    "bad prior block " << k);
    ROTOLIDAR_CHECK(x0_[k].size() == b.size, "linearisation point " << k << " has the wrong size");
    tangent += b.TangentSize();
    mutable_parameter_block_sizes()->push_back(b.size);
  }
  ROTOLIDAR_CHECK(J_.cols() == tangent && J_.rows() == r0_.size() && r0_.size() > 0,
                  "prior J is " << J_.rows() << "x" << J_.cols() << ", expected " << r0_.size() << "x" << tangent);
  set_num_residuals(static_cast<int>(r0_.size()));
}

std::unique_ptr<LinearizedPriorFactor> LinearizedPriorFactor::Gaussian(const BlockRef& block, const VectorXd& mean,
                                                                       const MatrixXd& information) {
  return std::make_unique<LinearizedPriorFactor>(std::vector<BlockRef>{block}, std::vector<VectorXd>{mean},
                                                 SqrtInformation(information),
                                                 VectorXd::Zero(information.rows()));
}

std::vector<double*> LinearizedPriorFactor::block_values() const {
  std::vector<double*> values;
  for (const BlockRef& b : blocks_) values.push_back(b.values);
  return values;
}

bool LinearizedPriorFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  VectorXd dx(J_.cols());
  std::vector<Matrix3d> Jl_inv(blocks_.size());
  int offset = 0;
  for (size_t k = 0; k < blocks_.size(); ++k) {
    if (blocks_[k].kind == BlockKind::kPose) {
      const PoseView x = ReadPose(parameters[k]), x0 = ReadPose(x0_[k].data());
      dx.segment<3>(offset) = x.t - x0.t;
      dx.segment<3>(offset + 3) = LogSO3(x.R * x0.R.transpose());
      Jl_inv[k] = LeftJacobianInverse(dx.segment<3>(offset + 3));
    } else {
      dx.segment(offset, blocks_[k].size) = Eigen::Map<const VectorXd>(parameters[k], blocks_[k].size) - x0_[k];
    }
    offset += blocks_[k].TangentSize();
  }
  Eigen::Map<VectorXd>(residuals, r0_.size()) = r0_ + J_ * dx;
  if (jacobians == nullptr) return true;
  offset = 0;
  for (size_t k = 0; k < blocks_.size(); ++k) {
    const BlockRef& b = blocks_[k];
    if (jacobians[k] != nullptr) {
      if (b.kind == BlockKind::kPose) {
        WriteAmbientPoseJacobian(J_.middleCols<3>(offset), J_.middleCols<3>(offset + 3) * Jl_inv[k],
                                 ReadPose(parameters[k]).q, jacobians[k]);
      } else {
        Eigen::Map<RowMajorXd>(jacobians[k], J_.rows(), b.size) = J_.middleCols(offset, b.size);
      }
    }
    offset += b.TangentSize();
  }
  return true;
}

// ----------------------------------------------------------------------------------------------- Marginalize

namespace {

struct Slot {
  BlockRef ref;
  int offset = 0;  ///< into the stacked tangent [dropped; kept]
};

/// Ceres' Corrector (Triggs et al., "Bundle adjustment - a modern synthesis", Sec. 4.3): the residual and
/// Jacobian whose Gauss-Newton step equals the robustified problem's, so the prior carries what the solver saw.
void ApplyLoss(const ceres::LossFunction* loss, VectorXd* r, MatrixXd* J) {
  if (loss == nullptr) return;
  const double sq_norm = r->squaredNorm();
  double rho[3];
  loss->Evaluate(sq_norm, rho);
  const double sqrt_rho1 = std::sqrt(std::max(rho[1], 0.0));
  if (sq_norm == 0.0 || rho[2] <= 0.0) {
    *r *= sqrt_rho1;
    *J *= sqrt_rho1;
    return;
  }
  const double D = 1.0 + 2.0 * sq_norm * rho[2] / rho[1];
  const double alpha = 1.0 - std::sqrt(D);
  *J = sqrt_rho1 * (*J - (alpha / sq_norm) * (*r) * (r->transpose() * (*J)));
  *r *= sqrt_rho1 / (1.0 - alpha);
}

/// Orders every block the terms reference: dropped first, then kept (first appearance). Returns the tangent size
/// of the dropped part, or -1 when two terms disagree about a block's size or kind.
int OrderBlocks(const std::vector<MarginalizationTerm>& terms, const std::vector<const double*>& dropped,
                std::vector<Slot>* slots) {
  std::vector<BlockRef> drop_refs, keep_refs;
  for (const MarginalizationTerm& term : terms) {
    for (const BlockRef& b : term.blocks) {
      auto same = [&](const BlockRef& o) { return o.values == b.values; };
      const bool is_dropped = std::find(dropped.begin(), dropped.end(), b.values) != dropped.end();
      std::vector<BlockRef>& list = is_dropped ? drop_refs : keep_refs;
      const auto it = std::find_if(list.begin(), list.end(), same);
      if (it == list.end()) {
        list.push_back(b);
      } else if (it->size != b.size || it->kind != b.kind) {
        return -1;
      }
    }
  }
  int offset = 0, dropped_size = 0;
  for (const std::vector<BlockRef>* list : {&drop_refs, &keep_refs}) {
    for (const BlockRef& b : *list) {
      slots->push_back(Slot{b, offset});
      offset += b.TangentSize();
    }
    if (list == &drop_refs) dropped_size = offset;
  }
  return dropped_size;
}

/// Linearises one term at the blocks' current values into rows [row, row + m) of the stacked tangent Jacobian
/// J_all (columns [dropped; kept]) and residual r_all. False when the cost fails or is not finite.
bool StackTerm(const MarginalizationTerm& term, const std::vector<Slot>& slots, int row, MatrixXd* J_all,
               VectorXd* r_all) {
  const int m = term.cost->num_residuals();
  const size_t nb = term.blocks.size();
  std::vector<const double*> params(nb);
  std::vector<RowMajorXd> J_ambient(nb);
  std::vector<double*> J_ptrs(nb);
  for (size_t k = 0; k < nb; ++k) {
    params[k] = term.blocks[k].values;
    J_ambient[k].resize(m, term.blocks[k].size);
    J_ptrs[k] = J_ambient[k].data();
  }
  VectorXd r(m);
  if (!term.cost->Evaluate(params.data(), r.data(), J_ptrs.data()) || !r.allFinite()) return false;
  MatrixXd J = MatrixXd::Zero(m, J_all->cols());  // this term's rows over the whole stacked tangent
  for (size_t k = 0; k < nb; ++k) {
    const auto it = std::find_if(slots.begin(), slots.end(),
                                 [&](const Slot& s) { return s.ref.values == term.blocks[k].values; });
    J.middleCols(it->offset, term.blocks[k].TangentSize()) += term.blocks[k].kind == BlockKind::kPose
        ? ToPoseTangentJacobian(J_ambient[k], params[k]) : MatrixXd(J_ambient[k]);
  }
  if (!J.allFinite()) return false;
  ApplyLoss(term.loss, &r, &J);
  J_all->middleRows(row, m) = J;
  r_all->segment(row, m) = r;
  return true;
}

/// The blocks' current values as linearisation points (pose quaternions normalised).
std::vector<VectorXd> CurrentValues(const std::vector<BlockRef>& blocks) {
  std::vector<VectorXd> x0;
  for (const BlockRef& b : blocks) {
    VectorXd value = Eigen::Map<const VectorXd>(b.values, b.size);
    if (b.kind == BlockKind::kPose) value.tail<4>().normalize();
    x0.push_back(value);
  }
  return x0;
}

}  // namespace

// The marginal of 1/2 |J dx + r|^2 over the dropped tangent, computed on J itself (orthogonal transformations)
// rather than on the normal equations: the IMU factor's information spans ~1e10 (bias random walk) to ~1e2, and
// H = J^T J would square that conditioning and cancel most digits of the Schur complement.
//   1. Pivoted QR of the dropped columns: Q^T J_d = [R_d; 0] (rank r_d).
//   2. Q^T [J_k, r]: its first r_d rows are satisfied exactly by the dropped variables; the rest is the marginal.
//   3. Pivoted QR of that rest compresses it to rank rows: J* = R_k P^T, r0 = (Q_k^T r)_head.
// Then J*^T J* = H_kk - H_kd H_dd^+ H_dk and J*^T r0 = b_k - H_kd H_dd^+ b_d.
MarginalizationResult Marginalize(const std::vector<MarginalizationTerm>& terms,
                                  const std::vector<const double*>& dropped, double rank_threshold) {
  MarginalizationResult result;
  std::vector<Slot> slots;
  const int nd = OrderBlocks(terms, dropped, &slots);
  if (nd < 0) {
    result.message = "Marginalize: terms disagree about a block's size or kind";
    return result;
  }
  const int n = slots.empty() ? 0 : slots.back().offset + slots.back().ref.TangentSize();
  const int nk = n - nd;
  if (nk == 0) {
    result.message = "Marginalize: no block is kept (nothing to carry the prior)";
    return result;
  }
  int rows = 0;
  for (const MarginalizationTerm& t : terms) rows += t.cost->num_residuals();
  MatrixXd J_all(rows, n);
  VectorXd r_all(rows);
  for (size_t t = 0, row = 0; t < terms.size(); row += terms[t].cost->num_residuals(), ++t) {
    if (!StackTerm(terms[t], slots, static_cast<int>(row), &J_all, &r_all)) {
      result.message = "Marginalize: term " + std::to_string(t) + " failed or is not finite";
      return result;
    }
  }
  MatrixXd rest(rows, nk + 1);  // [J_k, r], then rotated by the dropped columns' Q^T
  rest << J_all.rightCols(nk), r_all;
  int rank_d = 0;
  if (nd > 0) {
    Eigen::ColPivHouseholderQR<MatrixXd> qr_d(J_all.leftCols(nd));
    qr_d.setThreshold(rank_threshold);
    rank_d = static_cast<int>(qr_d.rank());
    rest.applyOnTheLeft(qr_d.householderQ().transpose());
  }
  if (rows == rank_d) {
    result.message = "Marginalize: the dropped blocks absorb every residual (the marginal carries no information)";
    return result;
  }
  const MatrixXd tail = rest.bottomRows(rows - rank_d);
  Eigen::ColPivHouseholderQR<MatrixXd> qr_k(tail.leftCols(nk));
  qr_k.setThreshold(rank_threshold);
  result.rank = static_cast<int>(qr_k.rank());
  if (result.rank == 0) {
    result.message = "Marginalize: the marginal carries no information";
    return result;
  }
  const VectorXd z = qr_k.householderQ().transpose() * tail.col(nk);
  MatrixXd R = qr_k.matrixR().topRows(result.rank).triangularView<Eigen::Upper>();
  MatrixXd J = R * qr_k.colsPermutation().transpose();
  std::vector<BlockRef> kept;
  for (const Slot& s : slots) {
    if (s.offset >= nd) kept.push_back(s.ref);
  }
  std::vector<VectorXd> x0 = CurrentValues(kept);
  result.prior = std::make_unique<LinearizedPriorFactor>(std::move(kept), std::move(x0), std::move(J),
                                                         z.head(result.rank));
  result.success = true;
  return result;
}

}  // namespace rotolidar
