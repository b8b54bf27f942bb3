#pragma once
// Rotor calibration from a static stretch (docs/calibration.md): the lever arm and tilt of the VLP-16 on the
// rotor (T_rotor_lidar) and the encoder zero that make the points seen at different rotor angles agree.
//
// With the base still, a point's base-frame position depends only on the calibration. Each outer iteration
// transforms every point with the current estimate (motor frame), sorts them into rotor-angle sectors, and
// measures sampled query points against the plane (PCA) of their nearest neighbours from the opposite sector
// (half a revolution away, where a calibration error moves them the other way); planes that are not flat enough
// are skipped. Ceres then minimises the Huber-robust point-to-plane residuals (rotor_residual.hpp) over the
// free parameters, the normals held; the next iteration re-associates with the new estimate. It stops when an
// iteration changes no parameter by more than the tolerances.
//
// Gauge: a rotation about the motor axis and a shift along it, applied to the whole static cloud, change no
// residual's truth; they are what the encoder zero (= the lidar's rotation about rotor z) and the lever arm along
// rotor z do. Those are held by default (RotorCalibOptions::estimate) and reported unobservable
// (calib_observability.cpp).
#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "bench/calib/calib_data.hpp"
#include "bench/calib/rotor_residual.hpp"
#include "core/types/calib.hpp"
#include "core/util/status.hpp"

namespace rotolidar::bench {

struct RotorCalibOptions {
  int sectors = 4;                   ///< rotor-angle sectors (even); queries meet the sector half a turn away
  int max_queries = 20000;           ///< query points, evenly sampled [-]
  int neighbours = 32;               ///< neighbours that define a query's plane (<= 32)
  double neighbour_radius_m = 0.4;   ///< neighbours farther than this from the query are not used [m]
  double max_plane_sigma_m = 0.04;   ///< the plane's thickness (sqrt of its smallest eigenvalue) at most [m]
  double min_planarity = 6.0;        ///< middle / smallest eigenvalue at least (a plane, not a line or a blob)
  /// Queries whose ray meets the plane more obliquely than this are not used [deg]: grazing returns are the
  /// noisiest and the most biased (beam footprint, mixed edge points).
  double max_incidence_deg = 75.0;
  double huber_m = 0.05;             ///< Huber loss scale of the point-to-plane residual [m]
  int max_outer_iterations = 8;      ///< re-associations
  int max_solver_iterations = 25;    ///< Ceres iterations per association
  double tolerance_m = 2e-5;         ///< converged when no lever component moves more than this [m] ...
  double tolerance_rad = 2e-5;       ///< ... and no angle (a time offset: times the rotor speed) more than this [rad]
  int threads = 2;
  /// Which parameters (CalibParam order) are estimated; the rest stay at the input calibration. Default: the
  /// lever arm across the rotor axis and the tilt about rotor x and y (what a static stretch observes).
  std::array<bool, kCalibParamCount> estimate{true, true, false, true, true, false, false, false};
  bool Validate(std::string* error) const;
};

/// One outer iteration: the association it used and where Ceres left the estimate.
struct CalibIteration {
  int associations = 0;
  double initial_cost = 0.0, final_cost = 0.0;  ///< Ceres' cost (1/2 sum of robust squared residuals) [m^2]
  double median_abs_residual_m = 0.0;           ///< before this iteration's solve
  int solver_iterations = 0;
  RotorCalibParams correction;                  ///< after the solve
};

/// A parameter's observability from the Gauss-Newton Hessian at the estimate (calib_observability.cpp).
struct ParamObservability {
  bool estimated = false;
  /// 1-sigma [m, rad or s] of this parameter if it were estimated together with the estimated ones (its own value
  /// when estimated); infinity where the Hessian gives it no information of its own.
  double sigma = 0.0;
  /// Share of its information not explained by the estimated parameters: 1 = independent, 0 = none of its own.
  double independence = 0.0;
  bool observable = false;  ///< independence > 1e-3 and sigma below 0.01 m, 0.01 rad or 1 ms
};

struct RotorCalibResult {
  RotorCalibParams correction;            ///< the estimate, a correction of the input calibration
  std::vector<CalibIteration> iterations;
  int solver_iterations = 0;              ///< Ceres iterations over all outer iterations
  bool converged = false;
  double residual_sigma_m = 0.0;          ///< robust residual standard deviation at the estimate [m]
  std::array<ParamObservability, kCalibParamCount> observability;
  Eigen::Matrix<double, kCalibParamCount, kCalibParamCount> hessian =
      Eigen::Matrix<double, kCalibParamCount, kCalibParamCount>::Zero();  ///< J^T W J at the estimate
};

/// The residual table of `points` under the input calibration (rotor_residual.hpp).
std::vector<ResidualPoint> PrepareResidualPoints(const std::vector<RotorPoint>& points, const RigCalib& calib);

/// The unit direction of a point's ray in the motor frame under the input rotation (corrections are far below a
/// degree; used for incidence tests and to orient normals towards the sensor).
Eigen::Vector3d RayDirectionMotor(const ResidualPoint& p);

/// Every point in the motor frame under `correction` (3 floats a point).
void MotorFramePoints(const std::vector<ResidualPoint>& table, const double* t0, const RotorCalibParams& correction,
                      std::vector<float>* xyz);

/// Sector of each point (rotor angle under `correction`, wrapped into [0, 2 pi)).
std::vector<int> RotorSectors(const std::vector<RotorPoint>& points, const RotorCalibParams& correction, int sectors);

/// The query / plane associations described in the file comment (`table` for the queries' ray directions).
std::vector<PlaneAssociation> AssociatePlanes(const std::vector<ResidualPoint>& table, const std::vector<float>& xyz,
                                              const std::vector<int>& sector, const RotorCalibOptions& options);

/// Signed residuals of `associations` under `correction` (normals as stored) [m].
std::vector<double> PlaneResiduals(const std::vector<ResidualPoint>& table, const double* t0,
                                   const std::vector<PlaneAssociation>& associations,
                                   const RotorCalibParams& correction);

/// The whole calibration (file comment). Fails on invalid options or when no plane association is found.
Status CalibrateRotor(const std::vector<RotorPoint>& points, const RigCalib& calib, const RotorCalibOptions& options,
                      RotorCalibResult* result);

/// Fills result->observability, hessian and residual_sigma_m at result->correction (calib_observability.cpp):
/// the Jacobian by central differences with each plane's normal refitted to its transformed neighbours, so that a
/// rigid motion of the whole cloud changes no residual.
void ComputeObservability(const std::vector<ResidualPoint>& table, const double* t0,
                          const std::vector<PlaneAssociation>& associations, const RotorCalibOptions& options,
                          RotorCalibResult* result);

}  // namespace rotolidar::bench
