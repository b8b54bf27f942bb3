// Rig imperfections (sim/rig/rig_errors.hpp): each error is applied with its configured magnitude, a zero config
// changes nothing, and a run with errors on is reproducible byte for byte.
#include "sim/rig/rig_errors.hpp"

#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"
#include "sim/rig/rig_physics.hpp"
#include "sim/sim_runner.hpp"
#include "sim/truth/truth.hpp"

namespace rotolidar::sim {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

std::string ReadBytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(RigErrors, ZeroConfigIsOffAndPresetsValidate) {
  std::string why;
  const RigErrorConfig zero;
  EXPECT_FALSE(zero.Enabled());
  EXPECT_TRUE(zero.Validate(&why)) << why;
  EXPECT_FALSE(RigErrorPreset(Realism::kIdeal).Enabled());
  for (Realism r : {Realism::kTypical, Realism::kHarsh}) {
    const RigErrorConfig c = RigErrorPreset(r);
    EXPECT_TRUE(c.Validate(&why)) << why;
    EXPECT_TRUE(c.CalibrationEnabled() && c.WobbleEnabled() && c.VibrationEnabled());
  }
  const RigErrorConfig t = RigErrorPreset(Realism::kTypical), h = RigErrorPreset(Realism::kHarsh);
  EXPECT_LT(t.calibration.rotor_lidar_tilt_sigma_deg, h.calibration.rotor_lidar_tilt_sigma_deg);
  EXPECT_LT(t.calibration.rotor_lidar_lever_sigma_m, h.calibration.rotor_lidar_lever_sigma_m);
  EXPECT_LT(t.wobble.cone_half_angle_rad, h.wobble.cone_half_angle_rad);
  RigErrorConfig bad;
  bad.calibration.rotor_lidar_tilt_sigma_deg = -1.0;
  EXPECT_FALSE(bad.Validate(&why));
  EXPECT_NE(why.find("rig_errors.calibration.rotor_lidar_tilt_sigma_deg"), std::string::npos) << why;
  bad = RigErrorConfig{};
  bad.vibration.harmonics = {{0, 0.1, 0.0, 0.0}};
  EXPECT_FALSE(bad.Validate(&why));
  EXPECT_NE(why.find("harmonics[0].order"), std::string::npos) << why;
}

TEST(RigErrors, YamlSectionParsesAndRejectsUnknownKeys) {
  SimConfig config = DefaultSimConfig();
  const YAML::Node ok = YAML::Load(
      "rig_errors:\n  calibration: {rotor_lidar_lever_sigma_m: 0.002}\n  wobble: {cone_half_angle_rad: 0.001}\n"
      "  vibration: {imbalance_accel_mps2: 0.1, harmonics: [{order: 50, accel_mps2: 0.2}]}\n");
  ASSERT_TRUE(ParseSimConfig("t.yaml", ok, &config).ok);
  EXPECT_EQ(config.rig_errors.calibration.rotor_lidar_lever_sigma_m, 0.002);
  EXPECT_EQ(config.rig_errors.wobble.cone_half_angle_rad, 0.001);
  ASSERT_EQ(config.rig_errors.vibration.harmonics.size(), 1u);
  EXPECT_EQ(config.rig_errors.vibration.harmonics[0].order, 50);
  // The resolved config writes the section back (it is enabled) and reads back to the same values.
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  EmitSimConfig(out, config);
  SimConfig again = DefaultSimConfig();
  ASSERT_TRUE(ParseSimConfig("again.yaml", YAML::Load(out.c_str()), &again).ok);
  EXPECT_EQ(again.rig_errors.vibration.harmonics[0].accel_mps2, 0.2);
  YAML::Emitter plain;
  EmitSimConfig(plain, DefaultSimConfig());
  EXPECT_EQ(std::string(plain.c_str()).find("rig_errors"), std::string::npos);  // off: not written
  const Status s = ParseSimConfig("t.yaml", YAML::Load("rig_errors: {wobble: {cone_deg: 1}}"), &config);
  EXPECT_FALSE(s.ok);
  EXPECT_NE(s.message.find("cone_deg"), std::string::npos) << s.message;
}

// Over many seeds the drawn errors are zero-mean Gaussians with the configured sigmas. With n = 4000 draws the
// sample sigma's relative standard error is 1/sqrt(2n) = 1.1 %: 5 % is > 4 standard errors; the mean's is
// sigma/sqrt(n) = 1.6 % of sigma: 7 % is > 4 of them.
TEST(RigErrors, DrawnCalibrationErrorsHaveTheConfiguredSigmas) {
  CalibErrorConfig c;
  c.rotor_lidar_lever_sigma_m = 0.002;
  c.rotor_lidar_tilt_sigma_deg = 0.2;
  c.encoder_zero_sigma_rad = 0.003;
  c.base_imu_translation_sigma_m = 0.004;
  c.base_imu_rotation_sigma_deg = 0.1;
  c.base_cam_translation_sigma_m = 0.005;
  c.base_cam_rotation_sigma_deg = 0.3;
  const int n = 4000;
  // Components: lever x, tilt x, tilt y, encoder, imu t x, imu r z, cam t y, cam r x.
  const double sigma[8] = {0.002, 0.2 * kDeg, 0.2 * kDeg, 0.003, 0.004, 0.1 * kDeg, 0.005, 0.3 * kDeg};
  double sum[8] = {}, sq[8] = {};
  for (int seed = 1; seed <= n; ++seed) {
    const CalibErrors e = DrawCalibErrors(c, seed);
    EXPECT_EQ(e.rotor_lidar_rotation_rad.z(), 0.0);  // tilt only
    const double v[8] = {e.rotor_lidar_translation_m.x(), e.rotor_lidar_rotation_rad.x(),
                         e.rotor_lidar_rotation_rad.y(), e.encoder_zero_rad, e.base_imu_translation_m.x(),
                         e.base_imu_rotation_rad.z(), e.base_cam_translation_m.y(), e.base_cam_rotation_rad.x()};
    for (int i = 0; i < 8; ++i) sum[i] += v[i], sq[i] += v[i] * v[i];
  }
  for (int i = 0; i < 8; ++i) {
    EXPECT_LT(std::abs(sum[i] / n), 0.07 * sigma[i]) << i;
    EXPECT_NEAR(std::sqrt(sq[i] / n) / sigma[i], 1.0, 0.05) << i;
  }
  const CalibErrors zero = DrawCalibErrors(CalibErrorConfig{}, 5);
  EXPECT_TRUE(zero.rotor_lidar_translation_m.isZero(0.0) && zero.base_cam_rotation_rad.isZero(0.0));
}

// calib.yaml's calibration is the true one with exactly the drawn errors; off, it is the true one bit for bit.
TEST(RigErrors, BelievedCalibIsTruthPlusTheDrawnErrors) {
  SimConfig config = DefaultSimConfig();
  config.seed = 11;
  const RigCalib truth = config.TrueCalib();
  const RigCalib off = config.BelievedCalib();
  EXPECT_TRUE(off.T_rotor_lidar.matrix() == truth.T_rotor_lidar.matrix());
  EXPECT_TRUE(off.T_base_imu.matrix() == truth.T_base_imu.matrix());
  EXPECT_EQ(off.encoder.zero_offset_rad, truth.encoder.zero_offset_rad);
  config.rig_errors = RigErrorPreset(Realism::kHarsh);
  const CalibErrors e = DrawCalibErrors(config.rig_errors.calibration, config.seed);
  const RigCalib b = config.BelievedCalib();
  EXPECT_LT((b.T_rotor_lidar.translation() - truth.T_rotor_lidar.translation() - e.rotor_lidar_translation_m)
                .norm(), 1e-15);
  EXPECT_LT((LogSO3(b.T_rotor_lidar.linear() * truth.T_rotor_lidar.linear().transpose()) -
             e.rotor_lidar_rotation_rad).norm(), 1e-12);
  EXPECT_LT((LogSO3(b.T_base_imu.linear() * truth.T_base_imu.linear().transpose()) - e.base_imu_rotation_rad)
                .norm(), 1e-12);
  EXPECT_LT((b.T_base_cam.translation() - truth.T_base_cam.translation() - e.base_cam_translation_m).norm(), 1e-15);
  EXPECT_EQ(b.encoder.zero_offset_rad, truth.encoder.zero_offset_rad + e.encoder_zero_rad);
  EXPECT_GT(e.rotor_lidar_rotation_rad.norm(), 0.0);
  EXPECT_TRUE(b.T_base_motor.matrix() == truth.T_base_motor.matrix());  // the motor mount is not perturbed
}

// A lever-arm error alone: every point of a plane seen through the believed calibration is displaced by the
// lever error turned into the base frame by the rotor, R_base_rotor(theta) * dt: its offset along the plane's
// normal is n . (R_base_rotor dt), at most |dt|, and it changes with the rotor angle (the plane gets blurred).
TEST(RigErrors, LeverArmErrorShiftsAPlaneByTheDrawnOffset) {
  SimConfig config = DefaultSimConfig();
  config.rig_errors.calibration.rotor_lidar_lever_sigma_m = 0.005;
  const RigCalib truth = config.TrueCalib(), believed = config.BelievedCalib();
  const Eigen::Vector3d dt = believed.T_rotor_lidar.translation() - truth.T_rotor_lidar.translation();
  ASSERT_GT(dt.norm(), 1e-4);
  const Eigen::Vector3d n(0, 0, 1);  // the floor 1.2 m below the base
  double lo = 1e9, hi = -1e9;
  for (int i = 0; i < 360; ++i) {
    const double theta = i * kDeg;
    const Pose3 T_true = truth.T_base_lidar(theta), T_bel = believed.T_base_lidar(theta);
    // A floor point as the lidar measures it (true geometry), reprojected with the believed calibration.
    const Eigen::Vector3d p_base(1.0 + 0.01 * i, -0.5, -1.2);
    const Eigen::Vector3d p_lidar = T_true.inverse() * p_base;
    const Eigen::Vector3d shift = T_bel * p_lidar - p_base;
    EXPECT_LT((shift - truth.T_base_rotor(theta).linear() * dt).norm(), 1e-12);
    lo = std::min(lo, n.dot(shift)), hi = std::max(hi, n.dot(shift));
  }
  // Over a full turn the normal offset sweeps the lever error's extent across the motor axis (the axis is
  // horizontal, along base x): from -|dt_xy| to +|dt_xy| in the rotor plane, within 1 degree of sampling.
  const double across = dt.head<2>().norm();
  EXPECT_NEAR(hi, across, across * 2e-4);
  EXPECT_NEAR(lo, -across, across * 2e-4);
}

// The wobble tilts the lidar's frame by exactly the cone's half angle at every rotor angle, in a direction that
// turns with the rotor relative to the ideal rotor frame; off, the kinematics are the calibration's bit for bit.
TEST(RigErrors, WobbleTiltsTheLidarByTheConeAngleAsTheRotorTurns) {
  const RigCalib truth = DefaultSimConfig().TrueCalib();
  const TrueRotorKinematics off(truth, AxisWobbleConfig{});
  for (double theta : {0.0, 1.0, 4.0})
    EXPECT_TRUE(off.T_base_lidar(theta).matrix() == truth.T_base_lidar(theta).matrix());
  AxisWobbleConfig w;
  w.cone_half_angle_rad = 0.05 * kDeg;
  const TrueRotorKinematics kin(truth, w);
  for (int i = 0; i < 72; ++i) {
    const double theta = i * 5.0 * kDeg;
    const Eigen::Matrix3d R_ideal_true =
        truth.T_base_rotor(theta).linear().transpose() * kin.T_base_rotor(theta).linear();
    const Eigen::Vector3d z = R_ideal_true.col(2);  // the true rotor z in the ideal rotor frame
    EXPECT_NEAR(std::acos(std::min(1.0, z.z())), w.cone_half_angle_rad, 1e-9) << theta;
    // The lidar frame as a whole is turned by the half angle from where calib.yaml puts it.
    const Eigen::Matrix3d R_lidar = truth.T_base_lidar(theta).linear().transpose() * kin.T_base_lidar(theta).linear();
    EXPECT_NEAR(LogSO3(R_lidar).norm(), w.cone_half_angle_rad, 1e-9) << theta;
    // The tilt's direction in the ideal rotor frame is at theta - 90 deg (a tilt about the axis at theta): it
    // turns once per revolution relative to the rotor (a tilt fixed in the rotor frame would be a calibration error).
    const Eigen::Vector2d dir = z.head<2>().normalized();
    EXPECT_NEAR(std::remainder(std::atan2(dir.y(), dir.x()) - (theta - M_PI / 2), 2 * M_PI), 0.0, 1e-6) << theta;
  }
  // A fixed axis tilt turns the motor axis by its angle.
  AxisWobbleConfig tilt;
  tilt.axis_tilt_rad = 0.2 * kDeg;
  const TrueRotorKinematics tilted(truth, tilt);
  const Eigen::Vector3d axis = tilted.T_base_rotor(0.7).linear().col(2), nominal = truth.T_base_motor.linear().col(2);
  EXPECT_NEAR(std::acos(axis.dot(nominal)), tilt.axis_tilt_rad, 1e-9);
}

/// Single-bin DFT of a 3-vector signal at frequency f, its mean (gravity) removed first so that it does not leak
/// into bins off the window's grid: (2/N) sum (x_k - mean) exp(-i 2 pi f t_k), per axis.
Eigen::Vector3cd Bin(const std::vector<std::pair<double, Eigen::Vector3d>>& x, double f_hz) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& [t, v] : x) mean += v / double(x.size());
  Eigen::Vector3cd c = Eigen::Vector3cd::Zero();
  for (const auto& [t, v] : x) c += (v - mean).cast<std::complex<double>>() * std::polar(1.0, -2 * M_PI * f_hz * t);
  return c * (2.0 / x.size());
}

/// The IMU on a still rig for 20 s with the given vibration (the runner's wiring: physics -> vibration -> IMU
/// model), samples after 2 s over a whole number of rotor revolutions; *f_r_hz = their mean rotor frequency.
void SimulateImu(const RotorVibrationConfig& vib, std::vector<std::pair<double, Eigen::Vector3d>>* accel,
                 std::vector<std::pair<double, Eigen::Vector3d>>* gyro, double* f_r_hz) {
  const SimConfig config = DefaultSimConfig();
  const RigCalib calib = config.TrueCalib();
  std::unique_ptr<RigModel> model;
  ASSERT_TRUE(RigModel::Create(config.rig_model, &model).ok);
  RigState state(*model);
  StepperDrive drive(config.motor, config.seed);
  ImuModel imu(config.imu, calib.T_base_imu, config.seed);
  const Pose3 T_world_base = MakePose(Eigen::Vector3d(0, 0, 1.2), Eigen::Quaterniond::Identity());
  const MotorReference r0 = drive.profile().Reference(0.0);
  state.Reset(T_world_base, r0.theta_rad, r0.omega_radps);
  const Eigen::Matrix3d R_imu_motor = calib.T_base_imu.linear().transpose() * calib.T_base_motor.linear();
  std::vector<double> theta;
  while (state.time_s() < 20.0) {
    const RotorJointState rotor = state.rotor_state();
    ASSERT_TRUE(state.Step(T_world_base, &drive).ok);
    if (state.step_count() % 5 != 1 || rotor.t_s < 2.0) continue;  // 200 Hz, after the start
    ImuTruth t = state.imu();
    AddRotorVibration(vib, R_imu_motor, rotor.theta_rad, rotor.omega_radps, &t.angular_rate_imu_radps,
                      &t.specific_force_imu_mps2);
    const ImuSample s = imu.SampleFromTruth(t.angular_rate_imu_radps, t.specific_force_imu_mps2, t.t_s);
    accel->push_back({t.t_s, s.accel_mps2});
    gyro->push_back({t.t_s, s.gyro_radps});
    theta.push_back(rotor.theta_rad);
  }
  // Keep whole revolutions so the rotor's line falls on a bin centre.
  const double revs = std::floor((theta.back() - theta.front()) / (2 * M_PI));
  size_t n = 0;
  while (n < theta.size() && theta[n] - theta.front() < revs * 2 * M_PI) ++n;
  accel->resize(n), gyro->resize(n);
  *f_r_hz = (theta[n - 1] - theta.front()) / (2 * M_PI * (accel->back().first - accel->front().first));
}

// The imbalance line sits at the rotor frequency and its harmonic at order x f_r, with the configured amplitudes:
// a vector of amplitude A turning in a plane gives a per-axis DFT bin vector of norm sqrt(2) A. Without the
// vibration the same bins hold the physics' own response (the rig model's 1 g m imbalance, the hinge's rocking),
// the bias walk's leakage and the IMU noise: measured 0.005 m/s^2 at f_r and 0.003 m/s^2 at 3 f_r, which the
// bounds below cover (with the vibration on: 0.0986 and 0.0516 m/s^2, gyro 0.00998 rad/s).
TEST(RigErrors, ImbalanceShowsAsASpectralLineAtTheRotorFrequency) {
  RotorVibrationConfig vib;
  vib.imbalance_accel_mps2 = 0.1;
  vib.imbalance_gyro_radps = 0.01;
  vib.reference_speed_radps = DefaultSimConfig().motor.profile.speed_radps;
  vib.harmonics = {{3, 0.05, 0.0, 0.4}};
  std::vector<std::pair<double, Eigen::Vector3d>> accel, gyro, accel0, gyro0;
  double f_r = 0.0, f_r0 = 0.0;
  SimulateImu(vib, &accel, &gyro, &f_r);
  SimulateImu(RotorVibrationConfig{}, &accel0, &gyro0, &f_r0);
  ASSERT_NEAR(f_r, vib.reference_speed_radps / (2 * M_PI), 0.01);
  const double a1 = Bin(accel, f_r).norm() / std::sqrt(2.0), a1_off = Bin(accel0, f_r).norm() / std::sqrt(2.0);
  const double a3 = Bin(accel, 3 * f_r).norm() / std::sqrt(2.0), a3_off = Bin(accel0, 3 * f_r).norm() / std::sqrt(2.0);
  const double g1 = Bin(gyro, f_r).norm() / std::sqrt(2.0);
  std::cout << "line amplitudes: accel f_r " << a1 << " (off " << a1_off << "), 3 f_r " << a3 << " (off " << a3_off
            << "), gyro f_r " << g1 << "\n";
  EXPECT_NEAR(a1, 0.1, 0.01);
  EXPECT_NEAR(a3, 0.05, 0.005);
  EXPECT_NEAR(g1, 0.01, 0.001);
  EXPECT_LT(a1_off, 0.01);
  EXPECT_LT(a3_off, 0.005);
  // Lines, not broadband: an order without a configured line (2 f_r, on the window's grid) holds what the run
  // without vibration holds there (the 0.1 m/s^2 line's leakage to off-grid bins would blur this, so none).
  EXPECT_LT(Bin(accel, 2 * f_r).norm() / std::sqrt(2.0), 0.01);
}

// End to end through the runner: off, calib.yaml is the true calibration and no rig-error truth is written; on,
// calib.yaml is the believed calibration, truth/ holds the true one and the drawn errors, the truth's lidar
// poses carry the wobble, the IMU carries the vibration on top of the same noise, and a rerun gives the same bytes.
TEST(RigErrors, RunnerWritesBelievedCalibAndTruthAndIsReproducible) {
  SimConfig config = DefaultSimConfig();
  config.duration_s = 1.0;
  config.camera.enabled = false;
  config.seed = 3;
  const fs::path root = fs::temp_directory_path() / "rotolidar_rig_errors_test";
  fs::remove_all(root);
  SimSummary summary;
  ASSERT_TRUE(RunSimulation(config, (root / "off").string(), &summary).ok);
  SimConfig on = config;
  on.rig_errors = RigErrorPreset(Realism::kHarsh);
  for (const char* name : {"on", "on_again"}) ASSERT_TRUE(RunSimulation(on, (root / name).string(), &summary).ok);

  EXPECT_FALSE(fs::exists(root / "off/truth/rig_errors.yaml"));
  RigCalib calib_off, calib_on, calib_true;
  ASSERT_TRUE(LoadCalibYaml((root / "off/calib.yaml").string(), &calib_off).ok);
  EXPECT_LT((calib_off.T_rotor_lidar.matrix() - config.TrueCalib().T_rotor_lidar.matrix()).norm(), 1e-15);
  ASSERT_TRUE(LoadCalibYaml((root / "on/calib.yaml").string(), &calib_on).ok);
  ASSERT_TRUE(LoadCalibYaml((root / "on/truth/calib_true.yaml").string(), &calib_true).ok);
  const RigCalib believed = on.BelievedCalib();
  EXPECT_LT((calib_on.T_rotor_lidar.matrix() - believed.T_rotor_lidar.matrix()).norm(), 1e-12);
  EXPECT_LT((calib_on.T_base_imu.matrix() - believed.T_base_imu.matrix()).norm(), 1e-12);
  EXPECT_NEAR(calib_on.encoder.zero_offset_rad, believed.encoder.zero_offset_rad, 1e-15);
  EXPECT_LT((calib_true.T_rotor_lidar.matrix() - on.TrueCalib().T_rotor_lidar.matrix()).norm(), 1e-12);
  RigErrorConfig read_config;
  CalibErrors read_errors;
  ASSERT_TRUE(ReadRigErrorTruth((root / "on").string(), &read_config, &read_errors).ok);
  EXPECT_EQ(read_errors.encoder_zero_rad, DrawCalibErrors(on.rig_errors.calibration, on.seed).encoder_zero_rad);
  EXPECT_EQ(read_config.vibration.harmonics.size(), on.rig_errors.vibration.harmonics.size());

  // Truth lidar poses = base * wobbled kinematics at the true rotor angle (1e-6: TUM text, shortest round trip).
  TruthLog truth;
  ASSERT_TRUE(ReadTruth((root / "on").string(), &truth).ok);
  const TrueRotorKinematics kin(on.TrueCalib(), on.rig_errors.wobble);
  ASSERT_EQ(truth.lidar.size(), truth.rotor.size());
  for (size_t i = 0; i < truth.lidar.size(); i += 97) {
    const Pose3 want = truth.base[i].T_ref_body * kin.T_base_lidar(truth.rotor[i].theta_rad);
    EXPECT_LT((truth.lidar[i].T_ref_body.matrix() - want.matrix()).norm(), 1e-9) << i;
  }

  // The IMU: the same noise, plus the vibration at the true rotor angle (speed by central differences).
  Recording rec_off, rec_on;
  ASSERT_TRUE(LoadRecording((root / "off").string(), &rec_off).ok);
  ASSERT_TRUE(LoadRecording((root / "on").string(), &rec_on).ok);
  ASSERT_EQ(rec_off.imu.size(), rec_on.imu.size());
  const RigCalib t = on.TrueCalib();
  const Eigen::Matrix3d R_imu_motor = t.T_base_imu.linear().transpose() * t.T_base_motor.linear();
  double max_err = 0.0, max_vib = 0.0;
  for (size_t k = 1; k + 1 < rec_on.imu.size(); ++k) {
    const size_t j = static_cast<size_t>(std::lround(rec_on.imu[k].t_s * on.truth_rate_hz));
    ASSERT_LT(j + 1, truth.rotor.size());
    const double omega = (truth.rotor[j + 1].theta_rad - truth.rotor[j - 1].theta_rad) * on.truth_rate_hz / 2;
    const RotorVibration v = RotorVibrationAt(on.rig_errors.vibration, truth.rotor[j].theta_rad, omega);
    const Eigen::Vector3d diff = rec_on.imu[k].accel_mps2 - rec_off.imu[k].accel_mps2;
    max_err = std::max(max_err, (diff - R_imu_motor * v.accel_motor_mps2).norm());
    max_vib = std::max(max_vib, v.accel_motor_mps2.norm());
  }
  EXPECT_GT(max_vib, 0.4);     // the harsh lines add up to ~0.6 m/s^2 at their peaks
  // The test's speed (central differences over 2 ms) differs from the hinge's instantaneous speed by the stepper's
  // microstep ripple, which the imbalance term (0.015 m/s^2 scaled by speed^2) carries: measured 5.5e-4 m/s^2.
  EXPECT_LT(max_err, 1e-3);

  for (const char* file : {"calib.yaml", "imu.csv", "lidar.pcap", "encoder.csv", "truth/lidar.tum",
                           "truth/rig_errors.yaml", "truth/calib_true.yaml"})
    EXPECT_EQ(ReadBytes(root / "on" / file), ReadBytes(root / "on_again" / file)) << file;
  EXPECT_NE(ReadBytes(root / "on/lidar.pcap"), ReadBytes(root / "off/lidar.pcap"));  // the wobble moved the rays
  fs::remove_all(root);
}

}  // namespace
}  // namespace rotolidar::sim
