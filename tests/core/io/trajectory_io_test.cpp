// Trajectory file I/O: write -> read round trips and file:line error messages.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/io/trajectory_io.hpp"

namespace rotolidar {
namespace {

std::string TempPath(const std::string& name) {
  return testing::TempDir() + "/rotolidar_traj_" + name;
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

/// A trajectory with non-round numbers in every field (times near a Unix epoch, as real data has).
Trajectory MakeTrajectory(double t0) {
  Trajectory traj;
  for (int i = 0; i < 50; ++i) {
    StampedPose sp;
    sp.t_s = t0 + 0.1 * i + 1e-7 * std::sin(i);
    const Eigen::Vector3d w(0.3 * std::sin(0.7 * i), 0.2 * std::cos(0.3 * i), 1.1 * i / 7.0);
    sp.T_ref_body.linear() = ExpSO3(w);
    sp.T_ref_body.translation() = Eigen::Vector3d(std::exp(0.01 * i), -1.0 / (i + 3), 1e3 * std::sin(i));
    traj.push_back(sp);
  }
  return traj;
}

void ExpectSame(const Trajectory& a, const Trajectory& b, double tol_t, double tol) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a[i].t_s, b[i].t_s, tol_t) << i;
    EXPECT_LE((a[i].T_ref_body.matrix() - b[i].T_ref_body.matrix()).cwiseAbs().maxCoeff(), tol) << i;
  }
}

TEST(TrajectoryIo, TumRoundTripIsExact) {
  const Trajectory traj = MakeTrajectory(1311868164.363181);
  const std::string path = TempPath("rt.tum");
  ASSERT_TRUE(WriteTrajectory(path, TrajectoryFormat::kTum, traj).ok);
  Trajectory back;
  const Status s = ReadTrajectory(path, TrajectoryFormat::kTum, &back);
  ASSERT_TRUE(s.ok) << s.message;
  // max_digits10 printing: times and translations come back bit-exact; rotation through a quaternion ~1e-15.
  ExpectSame(traj, back, 0.0, 1e-12);
  for (size_t i = 0; i < traj.size(); ++i) {
    EXPECT_EQ(traj[i].T_ref_body.translation(), back[i].T_ref_body.translation());
  }
}

TEST(TrajectoryIo, KittiRoundTripWithTimesIsExact) {
  const Trajectory traj = MakeTrajectory(12.5);
  const std::string path = TempPath("rt.kitti"), times = TempPath("rt.times");
  ASSERT_TRUE(WriteTrajectory(path, TrajectoryFormat::kKitti, traj).ok);
  ASSERT_TRUE(WriteKittiTimes(times, traj).ok);
  Trajectory back;
  Status s = ReadTrajectory(path, TrajectoryFormat::kKitti, &back, times);
  ASSERT_TRUE(s.ok) << s.message;
  ExpectSame(traj, back, 0.0, 0.0);  // the 12 matrix entries are printed directly: bit-exact
  // Without a times file the times are the indices.
  s = ReadTrajectory(path, TrajectoryFormat::kKitti, &back);
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(back[7].t_s, 7.0);
}

TEST(TrajectoryIo, EurocRoundTripToTheNanosecond) {
  const Trajectory traj = MakeTrajectory(1403715524.907143168);
  const std::string path = TempPath("rt.csv");
  ASSERT_TRUE(WriteTrajectory(path, TrajectoryFormat::kEuroc, traj).ok);
  Trajectory back;
  const Status s = ReadTrajectory(path, TrajectoryFormat::kEuroc, &back);
  ASSERT_TRUE(s.ok) << s.message;
  // Times are stored as integer ns; a double near 1.4e9 s resolves ~2.4e-7 s, so 1e-6 s bounds the round trip.
  ExpectSame(traj, back, 1e-6, 1e-12);
}

TEST(TrajectoryIo, EurocReadsExtraColumnsAndHeader) {
  const std::string path = TempPath("gt.csv");
  WriteText(path,
            "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n"
            "1403715524907143168,0.5,2.0,0.9,1,0,0,0,-0.002,-0.009\n");
  Trajectory traj;
  const Status s = ReadTrajectory(path, TrajectoryFormat::kEuroc, &traj);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(traj.size(), 1u);
  EXPECT_NEAR(traj[0].t_s, 1403715524.907143168, 1e-6);
  EXPECT_EQ(traj[0].T_ref_body.translation(), Eigen::Vector3d(0.5, 2.0, 0.9));
}

TEST(TrajectoryIo, BadFieldNamesFileLineAndField) {
  const std::string path = TempPath("bad.tum");
  WriteText(path, "# comment\n1.0 0 0 0 0 0 0 1\n\n2.0 0 0 abc 0 0 0 1\n");
  Trajectory traj(3);
  const Status s = ReadTrajectory(path, TrajectoryFormat::kTum, &traj);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find(path + ":4:"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("'z'"), std::string::npos) << s.message;
  EXPECT_EQ(traj.size(), 3u);  // untouched on failure
}

TEST(TrajectoryIo, WrongFieldCountAndBackwardsTimeAreErrors) {
  const std::string path = TempPath("bad2.tum");
  WriteText(path, "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  Trajectory traj;
  Status s = ReadTrajectory(path, TrajectoryFormat::kTum, &traj);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find(path + ":2:"), std::string::npos) << s.message;

  WriteText(path, "2.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n");
  s = ReadTrajectory(path, TrajectoryFormat::kTum, &traj);
  ASSERT_FALSE(s.ok);  // duplicates are kept (evo does), going backwards is not
  EXPECT_NE(s.message.find(path + ":3:"), std::string::npos) << s.message;

  WriteText(path, "1.0 0 0 0 0 0 0 0\n");
  s = ReadTrajectory(path, TrajectoryFormat::kTum, &traj);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("quaternion"), std::string::npos) << s.message;
}

TEST(TrajectoryIo, KittiErrors) {
  const std::string path = TempPath("bad.kitti"), times = TempPath("bad.times");
  WriteText(path, "1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 1 0 0 0 0 1 0\n");
  Trajectory traj;
  Status s = ReadTrajectory(path, TrajectoryFormat::kKitti, &traj);
  ASSERT_FALSE(s.ok);  // R has a 2 on the diagonal
  EXPECT_NE(s.message.find(path + ":2:"), std::string::npos) << s.message;

  WriteText(path, "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n");
  WriteText(times, "0.0\n");
  s = ReadTrajectory(path, TrajectoryFormat::kKitti, &traj, times);
  ASSERT_FALSE(s.ok);  // count mismatch
  EXPECT_NE(s.message.find(times), std::string::npos) << s.message;

  s = ReadTrajectory(TempPath("does_not_exist"), TrajectoryFormat::kKitti, &traj);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("does_not_exist"), std::string::npos);
}

TEST(TrajectoryIo, ParseFormatNames) {
  TrajectoryFormat f = TrajectoryFormat::kTum;
  EXPECT_TRUE(ParseTrajectoryFormat("kitti", &f));
  EXPECT_EQ(f, TrajectoryFormat::kKitti);
  EXPECT_STREQ(TrajectoryFormatName(f), "kitti");
  EXPECT_FALSE(ParseTrajectoryFormat("bag", &f));
}

}  // namespace
}  // namespace rotolidar
