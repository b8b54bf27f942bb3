// The estimator's camera path: tracking in the worker threads (frames decoded there from disk, or handed over
// decoded) gives exactly the observations of tracking in the caller's thread, whatever the worker's timing.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "core/pipeline/visual_frontend.hpp"
#include "tests/core/visual/tracker_test_scenes.hpp"

namespace rotolidar {
namespace {

using namespace visual::tracker_test;

struct StateObservations {
  std::vector<uint64_t> ids;
  std::vector<Eigen::Vector2d> normalized;
  int frames = 0;
};

enum class Source { kDecoded, kOnDisk };

/// Ten frames 0.1 s apart; a state at each frame's time, taken after the frames up to 0.1 s later were handed
/// over (the player's lead). Frames on disk are written as PNG (lossless) under `dir` first.
std::vector<StateObservations> RunStates(bool in_thread, Source source, const std::string& dir) {
  VisualConfig config;
  config.enabled = true;
  config.track_in_thread = in_thread;
  RigCalib calib;
  calib.camera = Pinhole();
  VisualFrontEnd frontend(config, calib);
  const cv::Mat canvas = MakeCanvas();
  constexpr int kFrames = 10;
  auto hand_over = [&](int k) {
    const CameraFrame frame = SequenceFrame(canvas, k);
    if (source == Source::kDecoded) return frontend.Track(frame);
    const std::string path = dir + "/" + std::to_string(k) + ".png";
    EXPECT_TRUE(cv::imwrite(path, frame.image));
    frontend.Track(CameraFrameRef{frame.t_s, path});
  };
  std::vector<StateObservations> out;
  hand_over(0);
  for (int k = 0; k < kFrames; ++k) {
    if (k + 1 < kFrames) hand_over(k + 1);
    VisualScanReport report;
    StateObservations s;
    for (const VisualObservation& o : frontend.ObservationsAt(0.1 * k, Pose3::Identity(), &report)) {
      s.ids.push_back(o.feature_id);
      s.normalized.push_back(o.normalized);
    }
    s.frames = report.frames_tracked;
    out.push_back(std::move(s));
  }
  return out;
}

TEST(VisualFrontEnd, TheTrackerThreadChangesNothing) {
  const std::string dir = (std::filesystem::temp_directory_path() / "rotolidar_visual_frontend_test").string();
  std::filesystem::create_directories(dir);
  const std::vector<StateObservations> inline_run = RunStates(false, Source::kDecoded, dir);
  for (Source source : {Source::kDecoded, Source::kOnDisk}) {
    const std::vector<StateObservations> threaded = RunStates(true, source, dir);
    ASSERT_EQ(threaded.size(), inline_run.size());
    for (size_t k = 0; k < inline_run.size(); ++k) {
      EXPECT_GT(inline_run[k].ids.size(), 100u) << "state " << k;
      EXPECT_EQ(threaded[k].ids, inline_run[k].ids) << "state " << k;
      EXPECT_EQ(threaded[k].normalized, inline_run[k].normalized) << "state " << k;
      EXPECT_EQ(threaded[k].frames, 1) << "state " << k;
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(VisualFrontEnd, AnUnreadableFrameIsSkipped) {
  VisualConfig config;
  config.enabled = true;
  RigCalib calib;
  calib.camera = Pinhole();
  VisualFrontEnd frontend(config, calib);
  frontend.Track(CameraFrameRef{0.0, "/nonexistent/frame.png"});
  VisualScanReport report;
  EXPECT_TRUE(frontend.ObservationsAt(0.0, Pose3::Identity(), &report).empty());
  EXPECT_FALSE(report.image);
  EXPECT_EQ(report.frames_tracked, 0);
}

}  // namespace
}  // namespace rotolidar
