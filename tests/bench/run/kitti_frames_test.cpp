// The KITTI frame check: ids missing from velodyne/ and bins without a point are warned about (with the ids),
// written into metrics.json, and fail the run under --strict before anything runs.
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include <gtest/gtest.h>

#include "bench/run/kitti_run.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

/// A sequence folder with calib.txt and the given bins (ids in `empty` get a 0-byte file).
std::string MakeSequence(const std::string& name, const std::vector<int>& ids, const std::vector<int>& empty) {
  const std::string dir = (fs::temp_directory_path() / ("rotolidar_kitti_frames_" + std::to_string(getpid())) /
                           name).string();
  fs::remove_all(dir);
  KittiDatasetLayout layout;
  layout.root = dir;
  EXPECT_TRUE(CreateKittiDatasetFolders(layout));
  EXPECT_TRUE(WriteKittiCalib(layout.CalibPath(), KittiCalib()));
  const std::vector<KittiPoint> one_ring = {{10.f, 0.f, 0.f, 0.5f}, {0.f, 10.f, 0.f, 0.5f}};
  for (int id : ids) EXPECT_TRUE(WriteKittiBin(layout.BinPath(id), one_ring));
  for (int id : empty) std::ofstream(layout.BinPath(id), std::ios::trunc).flush();
  return layout.SequenceDir();
}

std::vector<size_t> All(const KittiSequence& seq) {
  std::vector<size_t> picked(seq.frame_ids.size());
  for (size_t i = 0; i < picked.size(); ++i) picked[i] = i;
  return picked;
}

/// The default paths of a sequence folder.
KittiSequencePaths PathsOf(const std::string& dir) {
  KittiSequencePaths paths;
  paths.dir = dir;
  return paths;
}

TEST(KittiFrameCheck, ACompleteSequenceGivesNoWarning) {
  KittiSequence seq;
  ASSERT_TRUE(OpenKittiSequence(PathsOf(MakeSequence("complete", {0, 1, 2, 3}, {})), &seq));
  EXPECT_TRUE(CheckKittiFrames(seq, All(seq)).empty());
}

TEST(KittiFrameCheck, NamesMissingIdsAndEmptyBins) {
  KittiSequence seq;
  ASSERT_TRUE(OpenKittiSequence(PathsOf(MakeSequence("gaps", {0, 1, 4, 6, 9}, {5})), &seq));
  const std::vector<InputWarning> w = CheckKittiFrames(seq, All(seq));
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].code, "kitti.missing_frames");
  EXPECT_EQ(w[0].count, 4u);  // 2, 3, 7, 8
  EXPECT_NE(w[0].message.find("(ids 2-3, 7-8)"), std::string::npos) << w[0].message;
  EXPECT_NE(w[0].message.find("velodyne"), std::string::npos) << w[0].message;
  EXPECT_EQ(w[1].code, "kitti.empty_frames");
  EXPECT_EQ(w[1].count, 1u);
  EXPECT_NE(w[1].message.find("(ids 5)"), std::string::npos) << w[1].message;
  // Only the chosen frames count: from frame 6 on, 7-8 are missing and nothing is empty.
  const std::vector<InputWarning> tail = CheckKittiFrames(seq, {4, 5});
  ASSERT_EQ(tail.size(), 1u);
  EXPECT_EQ(tail[0].count, 2u);
}

TEST(KittiFrameCheck, StrictFailsBeforeRunningAndWritesNothing) {
  KittiRunOptions o;
  o.paths.dir = MakeSequence("strict", {0, 2}, {});
  o.out_dir = o.paths.dir + "/../out";
  o.strict = true;
  KittiRunResult r;
  const Status s = RunKitti(o, &r);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message.find("--strict: "), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("1 frame missing"), std::string::npos) << s.message;
  EXPECT_FALSE(fs::exists(o.out_dir + "/metrics.json"));
}

}  // namespace
}  // namespace rotolidar::bench
