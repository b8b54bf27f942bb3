#pragma once
// `rotolidar bench camera`: frames per second of the camera twin (sim/camera/) for each renderer (Embree ray
// casting, MuJoCo + OSMesa) and image size, along the scene's handheld path (kinematic, no physics): the render,
// the motion blur, the sensor model and the PNG encoding the recording writer does, each timed on the wall
// clock (rendering, blur and noise use `threads` threads). Medians over frames after one warm-up frame.
#include <ostream>
#include <string>
#include <vector>

#include "core/util/status.hpp"

namespace rotolidar::bench {

struct CameraBenchOptions {
  std::string scene = "lab";                   ///< scene name or path
  std::vector<std::string> renderers = {"embree", "osmesa"};
  std::vector<std::pair<int, int>> sizes = {{640, 480}, {1280, 720}};  ///< width, height [px]
  int frames = 60;                             ///< timed frames per renderer and size
  int threads = 2;
  std::string motion_blur = "velocity";        ///< none | velocity | subframes
  uint64_t seed = 1;
  bool Validate(std::string* error) const;
};

/// Median wall seconds per frame of each stage, for one renderer at one size.
struct CameraBenchRow {
  std::string renderer;
  int width = 0, height = 0;
  double render_s = 0.0, blur_s = 0.0, sensor_s = 0.0, png_s = 0.0;
  double frame_s = 0.0;      ///< render + blur + sensor (what a frame costs before it is written)
  double cpu_s = 0.0;        ///< CPU seconds of all the process's threads per frame (median)
  double mean_level = 0.0;   ///< mean 8-bit grey level of the frames (a sanity check that both see the scene)
};

/// Renders `frames` frames (plus one warm-up) per renderer and size. Fails with the scene's or renderer's error.
Status RunCameraBench(const CameraBenchOptions& options, std::vector<CameraBenchRow>* rows);
void PrintCameraBench(const CameraBenchOptions& options, const std::vector<CameraBenchRow>& rows, std::ostream& os);

}  // namespace rotolidar::bench
