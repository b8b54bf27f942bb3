// Point cloud files: PLY / PCD round trips through PCL, and the header guard that stops hostile counts before PCL
// allocates what they claim (inputs found by fuzzing LoadPointCloud).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/io/point_cloud_header.hpp"
#include "core/io/point_cloud_io.hpp"

namespace rotolidar {
namespace {

std::string TempPath(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "rotolidar_point_cloud_io_test";
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

std::string Write(const std::string& name, const std::string& bytes) {
  const std::string path = TempPath(name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

std::vector<Eigen::Vector3d> SomePoints() {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 50; ++i) points.emplace_back(0.25 * i, -0.5 * i, 1.0 + 0.125 * i);  // exact in float
  return points;
}

TEST(PointCloudIo, PlyAndPcdRoundTripExactly) {
  for (const std::string ext : {".ply", ".pcd"}) {
    const std::string path = TempPath("round_trip" + ext);
    ASSERT_TRUE(SavePointCloud(path, SomePoints()).ok);
    EXPECT_TRUE(CheckPointCloudHeader(path).ok) << ext;
    std::vector<Eigen::Vector3d> back;
    const Status st = LoadPointCloud(path, &back);
    ASSERT_TRUE(st.ok) << st.message;
    EXPECT_EQ(back, SomePoints()) << ext;
  }
}

TEST(PointCloudIo, EmptyFilesAreRefusedWithTheirName) {
  for (const std::string ext : {".ply", ".pcd"}) {
    const std::string path = Write("empty" + ext, "");
    std::vector<Eigen::Vector3d> points;
    const Status st = LoadPointCloud(path, &points);  // PCL 1.13's PCD reader dereferences null here
    EXPECT_FALSE(st.ok);
    EXPECT_NE(st.message.find(path + ": the file is empty"), std::string::npos) << st.message;
  }
}

TEST(PointCloudIo, PlyCountsMustFitTheFile) {
  const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex ";
  const std::string props = "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  const std::string data(24, '\0');  // two vertices of 12 bytes
  EXPECT_TRUE(CheckPointCloudHeader(Write("two.ply", header + "2" + props + data)).ok);
  // A negative count (PCL reads it as ~4 G vertices and allocates for them), a count the data cannot hold.
  Status st = CheckPointCloudHeader(Write("negative.ply", header + "-1" + props + data));
  EXPECT_NE(st.message.find("negative.ply: header line 3: element vertex: the count '-1' is not a whole number"),
            std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("three.ply", header + "3" + props + data));
  EXPECT_NE(st.message.find("header line 3: element vertex 3 needs at least 36 bytes of data, the file has 24"),
            std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("huge.ply", header + "99999999999999" + props + data));
  EXPECT_FALSE(st.ok);
  // ASCII: at least one byte per value.
  const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 4" + props;
  EXPECT_TRUE(CheckPointCloudHeader(Write("ascii.ply", ascii + "1 2 3\n4 5 6\n7 8 9\n1 1 1\n")).ok);
  EXPECT_FALSE(CheckPointCloudHeader(Write("ascii_short.ply", ascii + "1 2\n")).ok);
  // PCL skips header lines it cannot parse: an element line it skipped made it read ~10^17 property-less elements
  // (a hang found by fuzzing). Every line must be one the check understands, and end_header must come.
  st = CheckPointCloudHeader(Write("garbled.ply", "ply\nformat binary_little_endian 1.0\nend_\xff\xffply\n"));
  EXPECT_NE(st.message.find("header line 3: a control or non-ASCII byte"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("keyword.ply", "ply\nformat ascii 1.0\nelemental vertex 3\nend_header\n"));
  EXPECT_NE(st.message.find("header line 3: unknown PLY header keyword 'elemental'"), std::string::npos)
      << st.message;
  st = CheckPointCloudHeader(Write("endless.ply", "ply\nformat ascii 1.0\nelement vertex 0\n"));
  EXPECT_NE(st.message.find("no end_header line"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("not.ply", "plx\n"));
  EXPECT_NE(st.message.find("header line 1: not a PLY file"), std::string::npos) << st.message;
}

TEST(PointCloudIo, PcdHeadersMustBeCompleteAndFitTheFile) {
  auto header = [](const std::string& points) {
    return "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " + points +
           "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + points + "\n";
  };
  const std::string data(24, '\0');
  EXPECT_TRUE(CheckPointCloudHeader(Write("two.pcd", header("2") + "DATA binary\n" + data)).ok);
  Status st = CheckPointCloudHeader(Write("many.pcd", header("4000000000") + "DATA binary\n" + data));
  EXPECT_NE(st.message.find("many.pcd: header line 10: POINTS 4000000000 (binary) needs at least 48000000000 bytes"),
            std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("negative.pcd", header("-5") + "DATA ascii\n"));
  EXPECT_NE(st.message.find("header line 6: WIDTH: '-5' is not a whole number >= 0"), std::string::npos)
      << st.message;
  // Compressed data may expand, but not by more than LZF can.
  EXPECT_FALSE(CheckPointCloudHeader(Write("packed.pcd", header("1000000") + "DATA binary_compressed\n" + data)).ok);
  EXPECT_TRUE(CheckPointCloudHeader(Write("packed_ok.pcd", header("50") + "DATA binary_compressed\n" + data)).ok);
  // Structure: PCL 1.13 dereferences null on a header without FIELDS (found by fuzzing), so the guard checks that
  // every per-field list matches FIELDS and that POINTS = WIDTH x HEIGHT.
  const std::string no_fields = "SIZE 4 4 4\nTYPE F F F\nWIDTH 2\nPOINTS 2\nDATA ascii\n0 0 0\n1 1 1\n";
  st = CheckPointCloudHeader(Write("no_fields.pcd", no_fields));
  EXPECT_NE(st.message.find("header line 5: DATA before any FIELDS"), std::string::npos) << st.message;
  const std::string short_size = "FIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n1 2 3\n";
  st = CheckPointCloudHeader(Write("short_size.pcd", short_size));
  EXPECT_NE(st.message.find("FIELDS names 3 fields, but SIZE has 2, TYPE 3 and COUNT 3"), std::string::npos)
      << st.message;
  const std::string bad_points = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nPOINTS 3\nDATA ascii\n1 1 1\n";
  st = CheckPointCloudHeader(Write("bad_points.pcd", bad_points));
  EXPECT_NE(st.message.find("POINTS 3 is not WIDTH x HEIGHT"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("nul.pcd", std::string("FIELDS x y \0z\nSIZE 4 4 4\n", 25)));
  EXPECT_NE(st.message.find("header line 1: a control or non-ASCII byte"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("zero_height.pcd", "FIELDS x\nSIZE 4\nTYPE F\nWIDTH 2\nHEIGHT 0\nDATA ascii\n"));
  EXPECT_NE(st.message.find("header line 5: HEIGHT must be >= 1"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("zero_width.pcd", "FIELDS x\nSIZE 4\nTYPE F\nWIDTH 0\nHEIGHT 50\nDATA ascii\n"));
  EXPECT_NE(st.message.find("header line 4: WIDTH must be >= 1"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("twice.pcd", "FIELDS x\nSIZE 4\nSIZE 8\n"));
  EXPECT_NE(st.message.find("header line 3: SIZE appears twice"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("blank.pcd", "\t\t\nFIELDS x\nSIZE 4\n"));
  EXPECT_NE(st.message.find("header line 1: a header line must start with its keyword"), std::string::npos)
      << st.message;
  st = CheckPointCloudHeader(Write("count2.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 2 1 1\nWIDTH 1\n"
                                                 "DATA ascii\n1 2 3 4\n"));
  EXPECT_NE(st.message.find("header line 6: field x must be one 4-byte float (SIZE 4, TYPE F, COUNT 1)"),
            std::string::npos) << st.message;
  // ASCII data: POINTS lines of numbers, nothing else.
  const std::string xyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nDATA ascii\n";
  EXPECT_TRUE(CheckPointCloudHeader(Write("ascii_ok.pcd", xyz + "1 2 3\n\n4.5 nan -6e-3\n")).ok);
  st = CheckPointCloudHeader(Write("ascii_text.pcd", xyz + "1 2 3\nFIELDS 0\n"));
  EXPECT_NE(st.message.find("ascii_text.pcd: line 7: expected 3 numbers, found 2"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("ascii_word.pcd", xyz + "1 2 3\nx 0 1\n"));
  EXPECT_NE(st.message.find("line 7: 'x' is not a number"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("ascii_short.pcd", xyz + "1 2 3\n"));
  EXPECT_NE(st.message.find("POINTS is 2 but the data has 1 lines"), std::string::npos) << st.message;
  st = CheckPointCloudHeader(Write("bad_key.pcd", "FIELDS x\nSIZES 4\n"));
  EXPECT_NE(st.message.find("header line 2: unknown header keyword 'SIZES'"), std::string::npos) << st.message;
}

}  // namespace
}  // namespace rotolidar
