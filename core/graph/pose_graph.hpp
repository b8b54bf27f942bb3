#pragma once
// SE(3) pose graph over keyframes, the back end of the two-stage loop closure of the seed paper (LV-SLAM, Sensors
// 2025): keyframe poses T_world_kf are nodes, odometry and loop-closure relative poses are edges, and a Ceres
// Levenberg-Marquardt solve corrects the accumulated drift when a loop closes.
//
// Nodes: a pose T_world_node per caller-chosen integer id (keyframe ids; need not be dense). Ceres sees each as a
// translation block (3, m, world) plus a unit quaternion block (4, x y z w) on ceres::EigenQuaternionManifold.
// Gauge: every node added with fixed = true is held constant; when none is, the first node added is.
//
// Edges: a measured relative pose T_from_to with a 6x6 information matrix in the error coordinates of
// pose_graph_factors.hpp: e = [t(E); Log(R(E))], E = T_from_to_meas^-1 (T_world_from^-1 T_world_to), i.e. the
// right perturbation of the measurement, translation [m] first, rotation [rad] second, both expressed in the
// `to` frame. pose_graph_factors.hpp also has InformationInToFrame(), which converts an information matrix given
// in the `from`-frame convention of the rest of core/ (T (+) xi = (t + dt, Exp(dtheta) R), xi in frame `from`),
// and InformationFromCovariance(), a floored inverse of a registration covariance.
//
// Robust back end: odometry edges are trusted (plain least squares). Loop edges get a robust loss (default Cauchy
// after a Huber warm start, see PoseGraphConfig) so that a wrong loop's pull decays as its residual grows while a
// correct one still closes from a drifted start. After the solve, each loop edge's chi2 = e^T information e is
// compared with a threshold (default 16.81, the 99 % quantile of chi2 with 6 degrees of freedom); loops above it
// are rejected and, by default, the graph is re-solved without them so that they have no influence at all on the
// returned poses.
//
// Thread safety: PoseGraph is not thread-safe (no internal locking); use one instance per thread. It is copyable,
// so an integrator can copy the graph, optimise the copy in its own thread and read the poses back.
#include <array>
#include <cstddef>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

#include "core/graph/pose_graph_factors.hpp"
#include "core/types/geometry.hpp"
#include "core/types/trajectory.hpp"
#include "core/util/status.hpp"

namespace rotolidar::graph {

enum class EdgeKind { kOdometry, kLoop };

/// The robust loss put on loop edges. Ceres' loss functions act on s = chi2 = |r|^2 (whitened); `scale` a is
/// the whitened residual norm where down-weighting starts.
enum class LoopLossKind {
  kNone,    ///< plain least squares: a wrong loop bends the map (for comparison only)
  kHuber,   ///< rho(s) = s for s <= a^2, 2 a sqrt(s) - a^2 beyond: linear growth, bounded pull (not decaying)
  kCauchy,  ///< rho(s) = a^2 log(1 + s / a^2): the pull of a residual r decays as a^2 / |r| (default)
  kTukey,   ///< biweight: zero pull beyond |r| = a; can ignore a correct loop whose initial drift exceeds a
};

const char* ToString(EdgeKind kind);
const char* ToString(LoopLossKind kind);

struct PoseGraphConfig {
  /// The loss on loop edges. Cauchy: a wrong loop's pull decays (a^2 / |r| for |r| >> a, |r| the whitened residual
  /// norm), so it barely bends the map, and its chi2 then flags it. Its weakness: a correct loop whose initial
  /// residual is large (drift well beyond what the odometry information admits) is also barely pulled and can stay
  /// open. Hence the Huber warm start below. Dynamic Covariance Scaling (Agarwal et al., "Robust map optimization
  /// using dynamic covariance scaling", ICRA 2013) amounts to a similar redescending kernel; Ceres' Cauchy is used.
  LoopLossKind loop_loss = LoopLossKind::kCauchy;
  /// a [whitened residual norm, i.e. sqrt(chi2)]: sqrt(16.81) ~ 4.1, so inlier loops (chi2 below the rejection
  /// threshold) get weight >= 1/2 and stay close to least squares. > 0. Also the Huber warm start's scale.
  double loop_loss_scale = 4.1;
  /// With a redescending loop_loss (Cauchy, Tukey): first solve with HuberLoss(loop_loss_scale), whose pull on a
  /// loop never decays, from the input poses, then the robust solve from there. The convex first stage closes
  /// correct loops however far the odometry drifted (up to what the odometry information allows), the second
  /// lets wrong loops go slack again: graduated robustness in the spirit of GNC (Yang et al., "Graduated
  /// non-convexity for robust spatial perception", RA-L 2020) and of MM-estimators (a convex start, then a
  /// redescending refinement).
  bool huber_warm_start = true;
  int max_iterations = 100;              ///< Levenberg-Marquardt iterations per solve, >= 1
  /// Ceres: stop when |d cost| / cost < this; in (0, 1). Tighter than Ceres' 1e-6, which leaves ~1 mm between
  /// two solves of the same graph from different starts; pose graphs are cheap to iterate.
  double function_tolerance = 1e-8;
  /// A loop edge whose chi2 = e^T information e after the solve exceeds this is rejected (an outlier). 16.81 is
  /// the 99 % quantile of chi2 with 6 dof: a correct loop with an honest information matrix is rejected 1 % of the
  /// time. > 0.
  double loop_rejection_chi2 = 16.81;
  /// Re-solve without the rejected loops (from the robust solution), so rejected loops have zero influence.
  bool resolve_without_rejected = true;
  /// At most this many re-solves; a re-solve may reveal more rejected loops (each one then triggers another).
  /// Loops rejected after the last allowed re-solve are flagged but did take part in it. >= 1.
  int max_resolve_rounds = 3;
  int num_threads = 1;                   ///< Ceres threads, >= 1

  bool Validate(std::string* error) const;
};

/// A relative-pose constraint between two nodes.
struct PoseGraphEdge {
  int from_id = 0;
  int to_id = 0;
  Pose3 T_from_to = Pose3::Identity();  ///< measured T_from_to = T_world_from^-1 T_world_to
  /// Information of the error e (see the file comment: [translation m; rotation rad], in the `to` frame);
  /// units 1/m^2, 1/rad^2, 1/(m rad). Symmetric positive definite (checked by AddEdge).
  Matrix6d information = Matrix6d::Identity();
  EdgeKind kind = EdgeKind::kOdometry;
};

/// How one loop edge ended up after Optimize.
struct LoopEdgeReport {
  size_t edge_index = 0;  ///< position of the edge in PoseGraph::edges() (AddEdge order)
  int from_id = 0;
  int to_id = 0;
  double chi2 = 0.0;       ///< e^T information e at the returned poses (whitened squared residual norm)
  bool rejected = false;   ///< chi2 exceeded loop_rejection_chi2 after a solve that still contained the edge
};

struct PoseGraphResult {
  /// The robust solve and every re-solve ended with Ceres CONVERGENCE (false on bad input, see message). The Huber
  /// warm start is only a starting point and may stop at max_iterations.
  bool converged = false;
  int iterations = 0;       ///< Levenberg-Marquardt iterations, summed over the solves
  int num_solves = 0;       ///< Ceres solves: Huber warm start + robust solve + re-solves without rejected loops
  double initial_cost = 0.0;  ///< Ceres cost 0.5 sum rho(|r|^2) at the input poses, all edges, loop_loss
  double final_cost = 0.0;    ///< the same after the last solve (without the rejected loops when re-solved)
  double solve_time_s = 0.0;  ///< wall time of the solves [s]
  std::vector<LoopEdgeReport> loops;        ///< one per loop edge, in edge order
  std::vector<size_t> accepted_loop_edges;  ///< edge indices of loops kept
  std::vector<size_t> rejected_loop_edges;  ///< edge indices of loops rejected as outliers
  std::string message;                      ///< empty on success; why it failed or did not converge
};

/// Keyframe pose graph. Optimize() builds a fresh Ceres problem from all nodes and edges each time, so nodes and
/// edges may be added between calls; loop rejection is re-decided from scratch on every call.
class PoseGraph {
 public:
  explicit PoseGraph(PoseGraphConfig config = {});

  /// Adds a node. Fails on a duplicate id or a non-finite / non-orthonormal pose; the graph is then unchanged.
  Status AddNode(int id, const Pose3& T_world_node, bool fixed = false);
  /// Adds an edge. Fails, naming the edge (its would-be index and ids), on an unknown id, from == to, a non-finite
  /// or non-orthonormal T_from_to, or an information matrix that is not finite, symmetric and positive definite.
  Status AddEdge(const PoseGraphEdge& edge);

  /// Optimises the free nodes and writes them back in place (only when Ceres reports a usable solution; otherwise
  /// the poses stay as they were). Nodes in no edge of the last solve (isolated, or linked only by rejected loops)
  /// keep their input pose. Fails (converged = false, message) on an invalid config or an empty graph; a solve that
  /// hits max_iterations still writes its poses but reports converged = false.
  PoseGraphResult Optimize();

  /// The current pose of node `id`. Precondition: HasNode(id); violating it is a programmer error
  /// (ROTOLIDAR_CHECK throws rotolidar::InternalError). The reference stays valid until the next AddNode (Optimize
  /// updates the pose it refers to).
  const Pose3& Pose(int id) const;
  bool HasNode(int id) const;
  bool IsFixed(int id) const;     ///< held constant in Optimize (explicitly, or as the default gauge); false if absent
  std::vector<int> NodeIds() const;  ///< in insertion order
  size_t num_nodes() const { return nodes_.size(); }
  size_t num_edges() const { return edges_.size(); }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  const PoseGraphConfig& config() const { return config_; }

 private:
  struct Node {
    int id = 0;
    Pose3 T_world_node = Pose3::Identity();
    bool fixed = false;
  };

  void WriteBack(const std::vector<std::array<double, 7>>& params, const std::vector<bool>& fixed,
                 const std::vector<bool>& in_problem);
  void ReportLoops(const std::unordered_set<size_t>& rejected, PoseGraphResult* result) const;

  PoseGraphConfig config_;
  std::vector<Node> nodes_;                     // insertion order
  std::unordered_map<int, size_t> index_of_;    // id -> position in nodes_
  std::vector<PoseGraphEdge> edges_;
  std::vector<Matrix6d> sqrt_information_;      // S = L^T per edge (information = L L^T)
  bool any_fixed_ = false;
};

// ------------------------------------------------------------------------------------------ trajectory correction

/// A keyframe's pose before and after a graph correction, with its time stamp.
struct KeyframeCorrection {
  Seconds t_s = 0.0;
  Pose3 T_world_kf_old = Pose3::Identity();
  Pose3 T_world_kf_new = Pose3::Identity();
};

enum class CorrectionMode {
  /// T_new(t) = C_k T_old(t), C_k = T_world_kf_new * T_world_kf_old^-1 of the nearest keyframe with t_k <= t:
  /// each pose keeps its exact relative pose to that keyframe (jumps at keyframe times).
  kPrecedingKeyframe,
  /// Between bracketing keyframes k, k+1: Interpolate(C_k T_old(t), C_k+1 T_old(t), s), s = (t - t_k) /
  /// (t_k+1 - t_k), i.e. blend the two rigidly corrected poses (linear in translation, slerp in rotation), which
  /// does not depend on where the world origin is (blending the corrections C themselves would). Continuous.
  kInterpolate,
};

/// Maps time-stamped odometry poses (StampedPose::T_ref_body with ref = world, any body frame) onto the corrected
/// graph, in place. `keyframes` sorted by t_s (non-decreasing). Poses before the first keyframe use the first
/// correction, after the last the last one. A keyframe whose new pose equals its old one bit for bit applies no
/// correction, so a pose governed only by such keyframes stays bit-identical. The trajectory need not be sorted.
/// Fails (trajectory untouched) on no keyframes, unsorted or non-finite keyframe stamps, an invalid keyframe pose
/// (naming the keyframe index) or a non-finite trajectory stamp (naming the pose index).
Status CorrectTrajectory(const std::vector<KeyframeCorrection>& keyframes, CorrectionMode mode,
                         Trajectory* trajectory);

}  // namespace rotolidar::graph
