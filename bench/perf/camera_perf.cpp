// `rotolidar bench camera`: camera twin speed per renderer and image size (contract in camera_perf.hpp).
#include "bench/perf/camera_perf.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>

#include <opencv2/imgcodecs.hpp>

#include "bench/perf/perf_util.hpp"
#include "sim/camera/camera_stream.hpp"
#include "sim/rig/carrier_paths.hpp"
#include "sim/sim_config.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::bench {
namespace {

double NowS() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

/// The default camera scaled to another size at the same horizontal field of view.
sim::CameraConfig CameraAtSize(const CameraBenchOptions& o, int width, int height) {
  sim::CameraConfig c;
  const double scale = width / static_cast<double>(c.width_px);
  c.width_px = width;
  c.height_px = height;
  c.fx_px *= scale;
  c.fy_px *= scale;
  c.cx_px = 0.5 * width;
  c.cy_px = 0.5 * height;
  c.threads = o.threads;
  sim::ParseMotionBlurKind(o.motion_blur, &c.motion_blur);
  return c;
}

/// The scene's handheld path (or the default scripted loop when the scene has none).
Status MakeMotion(const sim::Scene& scene, std::unique_ptr<sim::BaseMotion>* motion) {
  sim::CarrierConfig carrier;
  const auto it = scene.default_paths.find("handheld");
  if (it != scene.default_paths.end()) {
    carrier.type = sim::CarrierType::kHandheld;
    carrier.handheld.waypoints = it->second;
  }
  return sim::MakeCarrierMotion(carrier, motion);
}

Status BenchOne(const CameraBenchOptions& o, const sim::Scene& scene, sim::EmbreeScene* embree,
                const sim::BaseMotion& motion, const std::string& renderer, int w, int h, CameraBenchRow* row) {
  sim::CameraConfig config = CameraAtSize(o, w, h);
  sim::ParseCameraRendererKind(renderer, &config.renderer);
  std::unique_ptr<sim::CameraSimulator> camera;
  if (Status s = sim::CameraSimulator::Create(config, o.seed, scene, embree, &camera); !s) return s;
  const Pose3 T_base_cam = sim::DefaultSimConfig().TrueCalib().T_base_cam;
  const auto pose = [&](Seconds t) { return Pose3(motion.At(t).T_world_base * T_base_cam); };
  std::vector<double> render, blur, sensor, png, total, cpu;
  double level = 0.0;
  cv::Mat image, grey;
  std::vector<uchar> encoded;
  for (int k = 0; k <= o.frames; ++k) {
    sim::CameraFrameStats st;
    const Seconds t = (k + 0.5) / config.rate_hz;
    const double cpu0 = ProcessCpuS();
    if (Status s = camera->RenderFrame(k, t, pose, &image, &st); !s) return s;
    const double cpu_s = ProcessCpuS() - cpu0;
    const double t0 = NowS();
    cv::imencode(".png", image, encoded);
    const double png_s = NowS() - t0;
    if (k == 0) continue;  // warm-up: caches, first-touch allocations
    render.push_back(st.render_s);
    blur.push_back(st.blur_s);
    sensor.push_back(st.sensor_s);
    png.push_back(png_s);
    total.push_back(st.render_s + st.blur_s + st.sensor_s);
    cpu.push_back(cpu_s);
    level += cv::mean(image)[0] / 3 + cv::mean(image)[1] / 3 + cv::mean(image)[2] / 3;
  }
  *row = {renderer, w, h, PerfMedian(render), PerfMedian(blur), PerfMedian(sensor), PerfMedian(png), PerfMedian(total), PerfMedian(cpu),
          level / o.frames};
  return Status::Ok();
}

}  // namespace

bool CameraBenchOptions::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) { return (error ? *error = "bench camera: " + m : m), false; };
  if (frames < 1 || frames > 100000) return fail("--frames must be in 1..100000");
  if (renderers.empty()) return fail("--renderer: embree, osmesa or both");
  for (const std::string& r : renderers) {
    sim::CameraRendererKind kind;
    if (!sim::ParseCameraRendererKind(r, &kind)) return fail("--renderer: embree, osmesa or both, got '" + r + "'");
  }
  sim::MotionBlurKind blur;
  if (!sim::ParseMotionBlurKind(motion_blur, &blur)) return fail("--blur: none, velocity or subframes");
  for (const auto& [w, h] : sizes) {
    std::string why;
    if (!CameraAtSize(*this, w, h).Validate(&why)) return fail("--sizes " + std::to_string(w) + "x" + std::to_string(h) + ": " + why);
  }
  return true;
}

Status RunCameraBench(const CameraBenchOptions& o, std::vector<CameraBenchRow>* rows) {
  std::string why;
  if (!o.Validate(&why)) return Status::Error(why);
  sim::Scene scene;
  if (Status s = sim::LoadScene(sim::ResolveScenePath(o.scene), &scene); !s) return s;
  std::unique_ptr<sim::EmbreeScene> embree;
  if (Status s = sim::EmbreeScene::Create(scene, &embree); !s) return s;
  std::unique_ptr<sim::BaseMotion> motion;
  if (Status s = MakeMotion(scene, &motion); !s) return s;
  rows->clear();
  for (const std::string& renderer : o.renderers) {
    for (const auto& [w, h] : o.sizes) {
      CameraBenchRow row;
      if (Status s = BenchOne(o, scene, embree.get(), *motion, renderer, w, h, &row); !s) return s;
      rows->push_back(row);
    }
  }
  return Status::Ok();
}

void PrintCameraBench(const CameraBenchOptions& o, const std::vector<CameraBenchRow>& rows, std::ostream& os) {
  os << "camera twin: scene " << o.scene << ", handheld path, " << o.frames << " frames (+1 warm-up), "
     << o.threads << " threads, motion blur " << o.motion_blur << "; medians per frame [ms]\n";
  os << "renderer  size        render    blur  sensor   frame  frames/s  CPU/frame     png  mean level\n";
  char line[256];
  for (const CameraBenchRow& r : rows) {
    std::snprintf(line, sizeof(line), "%-8s %5dx%-5d %7.2f %7.2f %7.2f %7.2f %9.1f %10.2f %7.2f %11.1f\n",
                  r.renderer.c_str(), r.width, r.height, 1e3 * r.render_s, 1e3 * r.blur_s, 1e3 * r.sensor_s,
                  1e3 * r.frame_s, 1.0 / r.frame_s, 1e3 * r.cpu_s, 1e3 * r.png_s, r.mean_level);
    os << line;
  }
  os << "frame = render + blur + sensor, wall clock (frames/s = 1 / frame); CPU/frame: CPU time of all the "
        "process's threads (OSMesa's llvmpipe threads included; on a loaded machine wall >> CPU / threads); png: "
        "cv::imencode of the frame (the recording writer's cost, one thread, not in frames/s)\n";
}

}  // namespace rotolidar::bench
