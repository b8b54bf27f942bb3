// KITTI odometry I/O: bit-exact write -> read round trips (bins, poses, times, calib), the sequence folder, strict
// errors that name file and line or byte offset, and the HDL-64E scan-line -> ring assignment on synthetic bins.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/io/kitti.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const std::string dir = testing::TempDir() + "/rotolidar_kitti_" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

void ExpectSameMatrix(const Pose3& a, const Pose3& b, size_t index) {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      EXPECT_TRUE(SameBits(a.matrix()(r, c), b.matrix()(r, c))) << "pose " << index << " (" << r << "," << c << ")";
}

/// Poses with non-round numbers everywhere (random rotation vectors, translations over 6 decades).
std::vector<Pose3> RandomPoses(size_t n) {
  RandomStream rng(7, "kitti-test-poses");
  std::vector<Pose3> poses;
  for (size_t i = 0; i < n; ++i) {
    Pose3 T = Pose3::Identity();
    T.linear() = ExpSO3(Eigen::Vector3d{rng.Normal(), rng.Normal(), rng.Normal()});
    T.translation() = Eigen::Vector3d{rng.Normal(0, 1e3), rng.Normal(0, 1e-3), rng.Normal()};
    poses.push_back(T);
  }
  return poses;
}

TEST(KittiIo, BinRoundTripIsBitExact) {
  RandomStream rng(7, "kitti-test-bin");
  std::vector<KittiPoint> points(1000);
  for (KittiPoint& p : points)
    p = {float(rng.Normal(0, 30)), float(rng.Normal(0, 30)), float(rng.Normal(0, 2)), float(rng.Uniform())};
  points[3].x_m = -0.0f;  // signed zero and a denormal survive too
  points[4].y_m = 1e-40f;
  const std::string path = TempDir("bin") + "/000000.bin";
  ASSERT_TRUE(WriteKittiBin(path, points));
  EXPECT_EQ(fs::file_size(path), 16u * points.size());
  std::vector<KittiPoint> back;
  ASSERT_TRUE(ReadKittiBin(path, &back));
  ASSERT_EQ(back.size(), points.size());
  EXPECT_EQ(std::memcmp(back.data(), points.data(), 16 * points.size()), 0);
}

TEST(KittiIo, PosesTimesAndCalibRoundTripBitExactly) {
  const std::string dir = TempDir("text");
  const std::vector<Pose3> poses = RandomPoses(200);
  ASSERT_TRUE(WriteKittiPoses(dir + "/poses.txt", poses));
  std::vector<Pose3> poses_back;
  ASSERT_TRUE(ReadKittiPoses(dir + "/poses.txt", &poses_back));
  ASSERT_EQ(poses_back.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) ExpectSameMatrix(poses[i], poses_back[i], i);

  std::vector<Seconds> times;
  for (int i = 0; i < 200; ++i) times.push_back(1.7e9 + 0.1037 * i + 1e-7 * std::sin(i));
  ASSERT_TRUE(WriteKittiTimeList(dir + "/times.txt", times));
  std::vector<Seconds> times_back;
  ASSERT_TRUE(ReadKittiTimeList(dir + "/times.txt", &times_back));
  ASSERT_EQ(times_back.size(), times.size());
  for (size_t i = 0; i < times.size(); ++i) EXPECT_TRUE(SameBits(times[i], times_back[i])) << i;

  KittiCalib calib;
  for (size_t j = 0; j < 4; ++j) calib.P[j] = Matrix34d::Random() * 700.0;
  calib.T_cam0_velo = RandomPoses(1)[0];
  ASSERT_TRUE(WriteKittiCalib(dir + "/calib.txt", calib));
  KittiCalib back;
  ASSERT_TRUE(ReadKittiCalib(dir + "/calib.txt", &back));
  for (size_t j = 0; j < 4; ++j)
    for (int k = 0; k < 12; ++k) EXPECT_TRUE(SameBits(calib.P[j](k / 4, k % 4), back.P[j](k / 4, k % 4))) << j;
  ExpectSameMatrix(calib.T_cam0_velo, back.T_cam0_velo, 0);
}

TEST(KittiIo, KittiOwnNumberFormatReadsBack) {  // the first line of KITTI 00's calib.txt and poses, as shipped
  const std::string dir = TempDir("format");
  WriteText(dir + "/p.txt",
            "1.000000e+00 9.043680e-12 2.326809e-11 5.551115e-17 9.043683e-12 1.000000e+00 2.392370e-10 "
            "3.330669e-16 2.326810e-11 2.392370e-10 9.999999e-01 -4.440892e-16\n\n");
  std::vector<Pose3> poses;
  ASSERT_TRUE(ReadKittiPoses(dir + "/p.txt", &poses));
  ASSERT_EQ(poses.size(), 1u);  // trailing empty lines are not frames
  EXPECT_EQ(poses[0].matrix()(2, 2), 9.999999e-01);
  EXPECT_EQ(poses[0].matrix()(2, 3), -4.440892e-16);
}

TEST(KittiIo, ShortBinNamesFileAndOffset) {
  const std::string path = TempDir("short") + "/000001.bin";
  std::vector<char> bytes(16 * 3 + 5, 0);
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  std::vector<KittiPoint> points(1);
  const Status s = ReadKittiBin(path, &points);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message.find(path), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("byte offset 48"), std::string::npos) << s.message;
  EXPECT_EQ(points.size(), 1u);  // untouched
  EXPECT_FALSE(ReadKittiBin(path + ".missing", &points));
}

struct BadText {
  const char* text;
  const char* expect;  ///< substring of the error after the path
};

TEST(KittiIo, MalformedPosesAndTimesNameFileLineAndField) {
  const std::string dir = TempDir("bad");
  const std::string good = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const BadText poses[] = {
      {"1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0\n", "p.txt:2: pose: expected 12 numbers, got 3"},
      {"1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 0x\n", "p.txt:2: pose field 11 = '0x'"},
      {"1 0 0 0 0 1 0 0 0 0 1 nan\n", "p.txt:1: pose field 11 = 'nan'"},
      {"2 0 0 0 0 1 0 0 0 0 1 0\n", "p.txt:1: pose: the 3x3 block is not a rotation"},
      {"\n1 0 0 0 0 1 0 0 0 0 1 0\n", "p.txt:1: empty line"},
      {"\n\n", "p.txt: no data"},
  };
  for (const BadText& b : poses) {
    WriteText(dir + "/p.txt", b.text);
    std::vector<Pose3> out;
    const Status s = ReadKittiPoses(dir + "/p.txt", &out);
    ASSERT_FALSE(s) << b.text;
    EXPECT_NE(s.message.find(b.expect), std::string::npos) << s.message;
    EXPECT_TRUE(out.empty());
  }
  const BadText times[] = {{"0\n0.1\n0.05\n", "t.txt:3: time 0.05 is earlier"}, {"0\n0.1 0.2\n", "t.txt:2: time:"}};
  for (const BadText& b : times) {
    WriteText(dir + "/t.txt", b.text);
    std::vector<Seconds> out;
    const Status s = ReadKittiTimeList(dir + "/t.txt", &out);
    ASSERT_FALSE(s) << b.text;
    EXPECT_NE(s.message.find(b.expect), std::string::npos) << s.message;
  }
  WriteText(dir + "/ok.txt", good);
  std::vector<Pose3> out;
  EXPECT_TRUE(ReadKittiPoses(dir + "/ok.txt", &out));
}

TEST(KittiIo, MalformedCalibNamesLineAndKey) {
  const std::string dir = TempDir("calib");
  const std::string row = " 1 0 0 0 0 1 0 0 0 0 1 0\n";
  const std::string all = "P0:" + row + "P1:" + row + "P2:" + row + "P3:" + row;
  const BadText cases[] = {
      {"P0: 1 2\n", "c.txt:1: P0: expected 12 numbers, got 2"},
      {"P5: 1\n", "c.txt:1: unknown key 'P5'"},
      {"P0 1 2\n", "c.txt:1: expected 'KEY: 12 numbers'"},
      {"P0: 1 0 0 0 0 1 0 0 0 0 1 0\nP0: 1 0 0 0 0 1 0 0 0 0 1 0\n", "c.txt:2: key 'P0' given twice"},
      {"P0:" "  1 0 0 0 0 1 0 0 0 0 1 0\n", "c.txt: key 'P1' missing"},
  };
  for (const BadText& b : cases) {
    WriteText(dir + "/c.txt", b.text);
    KittiCalib calib;
    const Status s = ReadKittiCalib(dir + "/c.txt", &calib);
    ASSERT_FALSE(s) << b.text;
    EXPECT_NE(s.message.find(b.expect), std::string::npos) << s.message;
  }
  WriteText(dir + "/c.txt", all);
  KittiCalib calib;
  const Status missing_tr = ReadKittiCalib(dir + "/c.txt", &calib);
  EXPECT_NE(missing_tr.message.find("key 'Tr' missing"), std::string::npos) << missing_tr.message;
  WriteText(dir + "/c.txt", all + "Tr: 1 0 0 0 0 1 0 0 0 0 -1 0\n");  // a reflection
  const Status reflection = ReadKittiCalib(dir + "/c.txt", &calib);
  EXPECT_NE(reflection.message.find("c.txt:5: Tr: the 3x3 block is not a rotation"), std::string::npos);
  WriteText(dir + "/c.txt", all + "Tr:" + row);
  EXPECT_TRUE(ReadKittiCalib(dir + "/c.txt", &calib));
}

TEST(KittiIo, Cam0ConventionIsTheConjugateByTr) {
  const std::vector<Pose3> T = RandomPoses(3);  // T[0] = Tr, T[1] = T_velo0_velok
  const Pose3 cam = VeloToCam0Pose(T[0], T[1]);
  EXPECT_LT((Cam0ToVeloPose(T[0], cam).matrix() - T[1].matrix()).cwiseAbs().maxCoeff(), 1e-9);
  // A point fixed in velo k, seen from cam0 of frame 0 both ways round.
  const Eigen::Vector3d p_velok(1.0, -2.0, 0.5);
  const Eigen::Vector3d a = T[0] * (T[1] * p_velok);           // velo k -> velo 0 -> cam0 0
  const Eigen::Vector3d b = cam * (T[0] * p_velok);            // velo k -> cam0 k -> cam0 0
  EXPECT_LT((a - b).norm(), 1e-9);
}

TEST(KittiIo, SequenceFolderFindsBinsTimesPosesAndChecksCoverage) {
  KittiDatasetLayout layout;
  layout.root = TempDir("dataset");
  layout.name = "07";
  ASSERT_TRUE(CreateKittiDatasetFolders(layout));
  for (int id : {0, 1, 3}) ASSERT_TRUE(WriteKittiBin(layout.BinPath(id), {KittiPoint{1.f, 2.f, 3.f, 0.5f}}));
  WriteText(layout.SequenceDir() + "/velodyne/README", "ignored");
  KittiCalib calib;
  ASSERT_TRUE(WriteKittiCalib(layout.CalibPath(), calib));
  KittiSequencePaths paths;
  paths.dir = layout.SequenceDir();

  KittiSequence seq;
  ASSERT_TRUE(OpenKittiSequence(paths, &seq)) << OpenKittiSequence(paths, &seq).message;  // no times, no poses
  EXPECT_EQ(seq.frame_ids, (std::vector<int>{0, 1, 3}));
  EXPECT_TRUE(seq.nominal_times);
  EXPECT_DOUBLE_EQ(seq.times[3], 0.3);
  EXPECT_TRUE(seq.poses.empty());

  ASSERT_TRUE(WriteKittiTimeList(layout.TimesPath(), {0.0, 0.1, 0.2}));  // frame 3 needs 4 lines
  Status s = OpenKittiSequence(paths, &seq);
  EXPECT_NE(s.message.find("times.txt: 3 lines, but"), std::string::npos) << s.message;
  ASSERT_TRUE(WriteKittiTimeList(layout.TimesPath(), {0.0, 0.1, 0.2, 0.3, 0.4}));
  ASSERT_TRUE(WriteKittiPoses(layout.PosesPath(), RandomPoses(4)));  // found through ../../poses/07.txt
  ASSERT_TRUE(OpenKittiSequence(paths, &seq)) << OpenKittiSequence(paths, &seq).message;
  EXPECT_FALSE(seq.nominal_times);
  EXPECT_EQ(seq.poses.size(), 4u);
  EXPECT_EQ(seq.bin_paths[2], layout.BinPath(3));

  paths.poses_path = layout.root + "/nope.txt";
  s = OpenKittiSequence(paths, &seq);
  EXPECT_NE(s.message.find("nope.txt: no such file"), std::string::npos) << s.message;
  paths.poses_path.clear();
  ASSERT_TRUE(WriteKittiBin(layout.SequenceDir() + "/velodyne/frame.bin", {}));
  s = OpenKittiSequence(paths, &seq);
  EXPECT_NE(s.message.find("frame.bin: a velodyne bin must be named by its frame number"), std::string::npos);
}

/// A synthetic HDL-64E bin: `lines` scan lines stored top first, each sweeping 0 -> 360 deg counter-clockwise
/// with the small back-steps real bins have, on a cylinder of radius 20 m.
std::vector<KittiPoint> SyntheticBin(int lines, int per_line) {
  std::vector<KittiPoint> bin;
  for (int l = 0; l < lines; ++l) {
    const double elevation_rad = (2.0 - 26.8 * l / (lines - 1)) * M_PI / 180.0;
    for (int i = 0; i < per_line; ++i) {
      double az_deg = 0.1 + 359.8 * i / per_line + (i % 7 == 3 ? -0.9 : 0.0);  // ~1 deg back-steps
      const double az = az_deg * M_PI / 180.0, r = 20.0;
      bin.push_back({float(r * std::cos(az)), float(r * std::sin(az)), float(r * std::tan(elevation_rad)),
                     float(i % 100) / 100.f});
    }
  }
  return bin;
}

TEST(KittiScan, ScanLinesBecomeRingsLowestFirst) {
  std::vector<KittiPoint> bin = SyntheticBin(64, 500);
  bin[10].x_m = std::nanf("");
  std::vector<ScanPoint> points;
  KittiScanStats stats;
  ASSERT_TRUE(KittiScanPoints(bin, 12.5, KittiScanConfig(), &points, &stats));
  EXPECT_EQ(stats.num_lines, 64u);
  EXPECT_EQ(stats.elevation_inversions, 0u);
  EXPECT_EQ(stats.num_nonfinite, 1u);
  ASSERT_EQ(points.size(), bin.size() - 1);
  EXPECT_EQ(points.front().ring, 63);  // top line first in the bin
  EXPECT_EQ(points.back().ring, 0);
  EXPECT_NEAR(stats.line_median_elevation_deg.front(), 2.0, 0.01);
  for (const ScanPoint& p : points) {
    EXPECT_NEAR(p.range_m, p.p_base.norm(), 1e-5);
    EXPECT_GE(p.t_s, 12.5);
    EXPECT_LT(p.t_s, 12.6);
    EXPECT_NEAR(p.t_s, 12.5 + 0.1 * p.azimuth_deg / 360.0, 1e-9);
    EXPECT_GE(p.azimuth_deg, 0.f);
    EXPECT_LT(p.azimuth_deg, 360.f);
  }
  EXPECT_NEAR(points[1].azimuth_deg, 0.1 + 359.8 / 500, 1e-3);  // counter-clockwise from +x
  EXPECT_FLOAT_EQ(points[1].intensity, 255.f * 0.01f);
}

TEST(KittiScan, TooManyLinesIsAnError) {
  std::vector<ScanPoint> points;
  const Status s = KittiScanPoints(SyntheticBin(300, 20), 0.0, KittiScanConfig(), &points);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message.find("300 scan lines"), std::string::npos) << s.message;
  KittiScanConfig bad;
  bad.scan_period_s = 0.0;
  EXPECT_FALSE(KittiScanPoints({}, 0.0, bad, &points));
}

TEST(KittiScan, AnEmptyBinGivesNoPoints) {
  std::vector<ScanPoint> points(3);
  KittiScanStats stats;
  ASSERT_TRUE(KittiScanPoints({}, 0.0, KittiScanConfig(), &points, &stats));
  EXPECT_TRUE(points.empty());
  EXPECT_EQ(stats.num_lines, 0u);
}

}  // namespace
}  // namespace rotolidar

namespace rotolidar {
namespace {

TEST(KittiIo, PointTimesAndSequenceInfoRoundTrip) {
  const std::string dir = TempDir("companions");
  const std::vector<float> times = {0.f, 1.5e-5f, 0.0999f, 0.f, 0.05f};
  ASSERT_TRUE(WriteKittiPointTimes(dir + "/t.bin", times));
  std::vector<float> back;
  ASSERT_TRUE(ReadKittiPointTimes(dir + "/t.bin", &back));
  EXPECT_EQ(back, times);
  std::ofstream(dir + "/t.bin", std::ios::app | std::ios::binary) << "xy";
  Status s = ReadKittiPointTimes(dir + "/t.bin", &back);
  EXPECT_NE(s.message.find("partial value starts at byte offset 20"), std::string::npos) << s.message;

  KittiSequenceInfo info;
  info.sensor = "VLP-16";
  info.scan_lines = 16;
  info.deskew = "estimator (an estimate)";
  info.source = "a: b";  // a colon inside a value
  ASSERT_TRUE(WriteKittiSequenceInfo(dir + "/info.txt", info));
  KittiSequenceInfo read;
  ASSERT_TRUE(ReadKittiSequenceInfo(dir + "/info.txt", &read));
  EXPECT_EQ(read.sensor, "VLP-16");
  EXPECT_EQ(read.scan_lines, 16);
  EXPECT_EQ(read.deskew, "estimator (an estimate)");
  EXPECT_EQ(read.source, "a: b");
  EXPECT_TRUE(read.point_order.empty());

  WriteText(dir + "/bad.txt", "# comment\nsensor: x\nlaser_count: 16\n");
  s = ReadKittiSequenceInfo(dir + "/bad.txt", &read);
  EXPECT_NE(s.message.find("bad.txt:3: unknown key 'laser_count'"), std::string::npos) << s.message;
  WriteText(dir + "/bad.txt", "scan_lines: 16.5\n");
  s = ReadKittiSequenceInfo(dir + "/bad.txt", &read);
  EXPECT_NE(s.message.find("bad.txt:1: scan_lines = '16.5'"), std::string::npos) << s.message;
  WriteText(dir + "/bad.txt", "sensor: a\n\nsensor: b\n");
  s = ReadKittiSequenceInfo(dir + "/bad.txt", &read);
  EXPECT_NE(s.message.find("bad.txt:3: key 'sensor' given twice"), std::string::npos) << s.message;
  info.sensor = "two\nlines";
  EXPECT_FALSE(WriteKittiSequenceInfo(dir + "/info.txt", info));
}

TEST(KittiIo, SequenceFolderReadsPointTimesAndInfo) {
  KittiDatasetLayout layout;
  layout.root = TempDir("dataset_times");
  ASSERT_TRUE(CreateKittiDatasetFolders(layout, true));
  for (int id : {0, 1}) ASSERT_TRUE(WriteKittiBin(layout.BinPath(id), {KittiPoint{1.f, 2.f, 3.f, 0.5f}}));
  ASSERT_TRUE(WriteKittiCalib(layout.CalibPath(), KittiCalib()));
  KittiSequencePaths paths;
  paths.dir = layout.SequenceDir();
  KittiSequence seq;
  ASSERT_TRUE(WriteKittiPointTimes(layout.PointTimesPath(0), {0.f}));
  Status s = OpenKittiSequence(paths, &seq);
  EXPECT_NE(s.message.find("velodyne_times/000001.bin: no such file"), std::string::npos) << s.message;
  ASSERT_TRUE(WriteKittiPointTimes(layout.PointTimesPath(1), {0.f}));
  KittiSequenceInfo info;
  info.scan_lines = 16;
  ASSERT_TRUE(WriteKittiSequenceInfo(layout.InfoPath(), info));
  s = OpenKittiSequence(paths, &seq);
  ASSERT_TRUE(s) << s.message;
  EXPECT_EQ(seq.point_time_paths, (std::vector<std::string>{layout.PointTimesPath(0), layout.PointTimesPath(1)}));
  EXPECT_EQ(seq.info.scan_lines, 16);
  EXPECT_EQ(seq.info_path, layout.InfoPath());
}

/// A rotary rig's revolution in its base frame: 16 rings of 400 points, each in firing order over 0.1 s, the
/// sensor's spin axis across base x and turned about it by the rotor during the sweep (so a ring's base-frame
/// azimuth atan2(y, x) does not sweep 0 -> 360: an azimuth split does not find the 16 rings). Stored top ring
/// first, as rotolidar exports.
void RotaryBin(std::vector<KittiPoint>* bin, std::vector<float>* times) {
  for (int ring = 15; ring >= 0; --ring) {
    const double elevation = (2.0 * ring - 15.0) * M_PI / 180.0;
    for (int i = 0; i < 400; ++i) {
      const double t = 0.1 * i / 400.0 + 2.304e-6 * ring;
      const double head = 2.0 * M_PI * 10.0 * t, rotor = 0.3 + 2.6 * t;  // head 10 Hz; rotor 2.6 rad/s
      const Eigen::Vector3d dir_lidar(std::cos(elevation) * std::cos(head), std::cos(elevation) * std::sin(head),
                                      std::sin(elevation));
      // Spin axis along base y, turned about base x by the rotor angle.
      const Eigen::Matrix3d R = Eigen::AngleAxisd(rotor, Eigen::Vector3d::UnitX()).toRotationMatrix() *
                                Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
      const Eigen::Vector3d p = R * dir_lidar * (5.0 + 0.01 * ring);
      bin->push_back({float(p.x()), float(p.y()), float(p.z()), 0.25f});
      times->push_back(float(t));
    }
  }
}

TEST(KittiScan, PointTimesSplitLinesWhereTheAzimuthCannot) {
  std::vector<KittiPoint> bin;
  std::vector<float> times;
  RotaryBin(&bin, &times);
  std::vector<ScanPoint> points;
  KittiScanStats stats;
  const Status by_azimuth = KittiScanPoints(bin, 50.0, KittiScanConfig(), &points, &stats);
  EXPECT_TRUE(!by_azimuth || stats.num_lines != 16u) << "azimuth split: " << stats.num_lines << " lines";

  ASSERT_TRUE(KittiScanPoints(bin, times, 50.0, KittiScanConfig(), &points, &stats));
  EXPECT_TRUE(stats.lines_from_times);
  EXPECT_EQ(stats.num_lines, 16u);
  EXPECT_EQ(stats.elevation_inversions, 0u);  // not checked for a time split
  ASSERT_EQ(points.size(), bin.size());
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(points[i].ring, 15 - int(i / 400)) << i;  // top ring first in the bin
    EXPECT_DOUBLE_EQ(points[i].t_s, 50.0 + double(times[i])) << i;
    // the head's sweep at the nominal 10 Hz: 360 deg * t / 0.1 s
    EXPECT_NEAR(points[i].azimuth_deg, std::fmod(3600.0 * double(times[i]), 360.0), 1e-3) << i;
  }
  const Status mismatch = KittiScanPoints(bin, std::vector<float>(3, 0.f), 0.0, KittiScanConfig(), &points);
  EXPECT_NE(mismatch.message.find("6400 points has 3 point times"), std::string::npos) << mismatch.message;
}

}  // namespace
}  // namespace rotolidar
