// The loop closer's visual stage 1 (the seed's): keyframes carry camera images, the ORB bag of words proposes, the
// LiDAR descriptor and GICP confirm. Synthetic: the two-lap yard of loop_closer_test.cpp, and as each keyframe's
// image a noisy view of a textured "place" named after its 10 m cell on the truth path.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/graph/loop_closer.hpp"
#include "tests/core/graph/synthetic_walk.hpp"
#include "tests/core/loop/synthetic_images.hpp"

namespace rotolidar::graph {
namespace {

const std::string kVocabulary = std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes/vocabulary/twin_orb_k8_l5.bin";

// alias: every place shows the same texture (repeated bays, blank walls): the camera cannot tell places apart.
cv::Mat ImageAt(const Pose3& T_truth, int step, bool alias) {
  const Eigen::Vector3d p = T_truth.translation();
  const std::string place = alias ? "everywhere" : "cell-" + std::to_string(int(std::floor(p.x() / 10.0))) + "-" +
                            std::to_string(int(std::floor(p.y() / 10.0)));
  return loop::test_util::MakeView(loop::test_util::MakePlace(place), 4.0 * std::sin(step), 3.0 * std::cos(step),
                                   2.0 * std::sin(0.7 * step), 1.0, 0.0, "noise-" + std::to_string(step));
}

LoopClosureState RunVisualWalk(bool load_vocabulary, bool alias, std::vector<Pose3>* truth_at_keyframes,
                               std::vector<KeyframeCloud>* clouds = nullptr) {
  const std::vector<Eigen::Vector3d> world = test_util::MakeWorld(7);
  test_util::Walk walk = test_util::MakeWalk();
  walk.truth.resize(400), walk.odometry.resize(400);  // a lap and a quarter
  LoopClosureConfig config;
  config.enabled = true, config.threaded = false, config.map_voxel_m = 0.0, config.keyframe_spacing_m = 2.0;
  LoopCloser closer(config);
  if (load_vocabulary) {
    const Status s = closer.LoadVocabulary(kVocabulary);
    EXPECT_TRUE(s) << s.message;
  }
  for (size_t i = 0; i < walk.truth.size(); ++i) {
    KeyframeInput kf;
    kf.t_s = 0.5 * double(i);
    kf.T_world_base = walk.odometry[i];
    kf.points_base = test_util::Observe(world, walk.truth[i]);
    kf.image = ImageAt(walk.truth[i], int(i), alias);
    closer.AddKeyframe(std::move(kf));
  }
  closer.Finish();
  LoopClosureState s = closer.State();
  if (clouds) *clouds = closer.KeyframeClouds();
  for (const KeyframePose& k : s.keyframes) truth_at_keyframes->push_back(walk.truth[size_t(std::lround(k.t_s / 0.5))]);
  return s;
}

TEST(LoopCloserVisual, TheBagOfWordsProposesAndGeometryConfirms) {
  std::vector<Pose3> truth;
  std::vector<KeyframeCloud> clouds;
  const LoopClosureState s = RunVisualWalk(true, false, &truth, &clouds);
  // Each stored keyframe hands out its word vector (what bench loops rates offline), L1-normalised.
  ASSERT_EQ(clouds.size(), s.keyframes.size());
  for (const KeyframeCloud& k : clouds) {
    ASSERT_FALSE(k.bow.empty()) << k.id;
    double sum = 0.0;
    for (const auto& word : k.bow) sum += word.second;
    EXPECT_NEAR(sum, 1.0, 1e-9) << k.id;
  }
  size_t visual = 0, graph = 0, descriptor_rejected = 0;
  for (const CandidateRecord& c : s.candidates) {
    visual += c.source == CandidateRecord::Source::kVisual;
    graph += c.source == CandidateRecord::Source::kGraph;
    descriptor_rejected += c.outcome == CandidateRecord::Outcome::kDescriptorRejected;
  }
  std::printf("keyframes %zu (%zu with an image), candidates %zu (%zu visual, %zu graph, %zu stopped by the LiDAR "
              "descriptor), loops %zu\n", s.keyframes.size(), s.visual_keyframes, s.candidates.size(), visual, graph,
              descriptor_rejected, s.loops.size());
  EXPECT_EQ(s.visual_keyframes, s.keyframes.size());
  // With images, stage 1 is the camera's; the only other proposals are the graph's fallback.
  EXPECT_GT(visual, 0u);
  EXPECT_EQ(visual + graph, s.candidates.size());
  ASSERT_GT(s.loops.size(), 0u);
  for (const LoopRecord& l : s.loops) {  // every loop is a true revisit with GICP's relative pose
    const Pose3 err = (truth[l.match_id].inverse() * truth[l.query_id]).inverse() * l.T_match_query;
    EXPECT_LT(err.translation().norm(), 0.01) << l.query_id << " -> " << l.match_id;
  }
}

TEST(LoopCloserVisual, LookAlikeImagesAreStoppedByTheLidar) {
  std::vector<Pose3> truth;
  const LoopClosureState s = RunVisualWalk(true, true, &truth);
  size_t stopped = 0;
  for (const CandidateRecord& c : s.candidates)
    stopped += c.outcome != CandidateRecord::Outcome::kAccepted && c.outcome != CandidateRecord::Outcome::kGraphError;
  std::printf("look-alike images: candidates %zu, %zu stopped by the LiDAR (descriptor, distance, GICP, drift), "
              "loops %zu\n", s.candidates.size(), stopped, s.loops.size());
  EXPECT_GT(stopped, 0u);  // the camera proposed places the LiDAR knew to be elsewhere
  for (const LoopRecord& l : s.loops) {  // and no wrong loop got through
    const Pose3 err = (truth[l.match_id].inverse() * truth[l.query_id]).inverse() * l.T_match_query;
    EXPECT_LT(err.translation().norm(), 0.01) << l.query_id << " -> " << l.match_id;
  }
}

TEST(LoopCloserVisual, WithoutAVocabularyImagesAreIgnored) {
  std::vector<Pose3> truth;
  std::vector<KeyframeCloud> clouds;
  const LoopClosureState s = RunVisualWalk(false, false, &truth, &clouds);
  EXPECT_EQ(s.visual_keyframes, 0u);
  ASSERT_FALSE(clouds.empty());
  for (const KeyframeCloud& k : clouds) EXPECT_TRUE(k.bow.empty()) << k.id;
  for (const CandidateRecord& c : s.candidates) EXPECT_NE(c.source, CandidateRecord::Source::kVisual);
  LoopClosureConfig config;
  LoopCloser closer(config);
  const Status bad = closer.LoadVocabulary("/nonexistent/vocabulary.bin");
  EXPECT_FALSE(bad);
  EXPECT_NE(bad.message.find("/nonexistent/vocabulary.bin"), std::string::npos) << bad.message;
  EXPECT_FALSE(closer.has_vocabulary());
}

}  // namespace
}  // namespace rotolidar::graph
