// One camera frame = render(s) at the true pose + motion blur + sensor; the stream schedules and writes them.
#include "sim/camera/camera_stream.hpp"

#include <chrono>

#include "sim/camera/embree_camera.hpp"
#include "sim/camera/osmesa_camera.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

double NowS() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

Status CameraSimulator::Create(const CameraConfig& config, uint64_t run_seed, const Scene& scene,
                               EmbreeScene* embree, std::unique_ptr<CameraSimulator>* out) {
  ROTOLIDAR_CHECK(out != nullptr, "CameraSimulator::Create needs an output");
  std::string why;
  if (!config.Validate(&why)) return Status::Error(why);
  std::unique_ptr<CameraSimulator> sim(new CameraSimulator());
  sim->config_ = config;
  sim->run_seed_ = run_seed;
  if (config.renderer == CameraRendererKind::kEmbree) {
    if (!embree) return Status::Error("camera: the embree renderer needs the scene's EmbreeScene");
    std::unique_ptr<EmbreeCameraRenderer> r;
    if (Status s = EmbreeCameraRenderer::Create(scene, embree, config, &r); !s) return s;
    sim->rays_ = r->rays();
    sim->renderer_ = std::move(r);
  } else {
    std::unique_ptr<OsmesaCameraRenderer> r;
    if (Status s = OsmesaCameraRenderer::Create(scene, config, &r); !s) return s;
    sim->rays_ = r->rays();
    sim->renderer_ = std::move(r);
  }
  *out = std::move(sim);
  return Status::Ok();
}

Status CameraSimulator::RenderAt(Seconds t_mid_s, double dt_s, const CameraPoseFn& T_world_cam_at,
                                 RadianceImage* out) {
  const int h = config_.height_px;
  if (config_.readout_s > 0.0) {
    row_poses_.resize(static_cast<std::size_t>(h));
    for (int v = 0; v < h; ++v) {
      const double row_offset_s = (static_cast<double>(v) / (h - 1) - 0.5) * config_.readout_s;
      row_poses_[static_cast<std::size_t>(v)] = T_world_cam_at(t_mid_s + dt_s + row_offset_s);
    }
  } else {
    row_poses_.assign(1, T_world_cam_at(t_mid_s + dt_s));
  }
  return renderer_->Render(t_mid_s + dt_s, row_poses_, out);
}

Status CameraSimulator::RenderFrame(long index, Seconds t_mid_s, const CameraPoseFn& T_world_cam_at, cv::Mat* bgr8,
                                    CameraFrameStats* stats) {
  CameraFrameStats st;
  const double exposure = config_.exposure_s;
  double t0 = NowS();
  if (config_.motion_blur == MotionBlurKind::kSubframes) {
    // Average of renders spread evenly over the exposure (the depth is the middle one's, or the nearest).
    const int n = config_.blur_subframes;
    for (int j = 0; j < n; ++j) {
      const double dt = ((j + 0.5) / n - 0.5) * exposure;
      if (Status s = RenderAt(t_mid_s, dt, T_world_cam_at, &sub_); !s) return s;
      if (j == 0) blurred_ = sub_;
      else
        for (std::size_t i = 0; i < sub_.rgb.size(); ++i) blurred_.rgb[i] += sub_.rgb[i];
      if (j == n / 2) blurred_.depth_m = sub_.depth_m;
    }
    for (float& x : blurred_.rgb) x /= static_cast<float>(n);
    st.render_s = NowS() - t0;
  } else {
    if (Status s = RenderAt(t_mid_s, 0.0, T_world_cam_at, &sharp_); !s) return s;
    st.render_s = NowS() - t0;
    t0 = NowS();
    if (config_.motion_blur == MotionBlurKind::kVelocity) {
      const Pose3 T_world_mid = T_world_cam_at(t_mid_s);
      const Pose3 T_mid_world = T_world_mid.inverse();
      ExposureMotion motion{T_mid_world * T_world_cam_at(t_mid_s - 0.5 * exposure),
                            T_mid_world * T_world_cam_at(t_mid_s + 0.5 * exposure)};
      st.blur_px = ApplyVelocityBlur(config_.Intrinsics(), rays_, motion, sharp_, config_.threads, &blurred_);
    } else {
      blurred_ = sharp_;
    }
    st.blur_s = NowS() - t0;
  }
  t0 = NowS();
  ExposeSensor(config_, blurred_, FrameNoiseSeed(run_seed_, index), config_.threads, bgr8);
  st.sensor_s = NowS() - t0;
  if (stats) *stats = st;
  return Status::Ok();
}

Status CameraStream::RenderCovered(const RigTrace& trace, Seconds duration_s, RecordingWriter* writer,
                                   TruthWriter* truth) {
  const double half = camera_->half_span_s();
  const auto T_world_cam_at = [&](Seconds t) { return Pose3(trace.At(t).T_world_base * T_base_cam_); };
  while (true) {
    const Seconds t = FrameTime(next_);
    if (t + half > duration_s || trace.empty() || !trace.Covers(t - half, t + half)) return Status::Ok();
    CameraFrameStats stats;
    if (Status s = camera_->RenderFrame(next_, t, T_world_cam_at, &image_, &stats); !s) return s;
    total_.render_s += stats.render_s;
    total_.blur_s += stats.blur_s;
    total_.sensor_s += stats.sensor_s;
    total_.blur_px = std::max(total_.blur_px, stats.blur_px);
    if (Status s = writer->Write(CameraFrame{clock_.Stamp(t), image_}); !s) return s;
    if (Status s = truth->WriteCam({t, T_world_cam_at(t)}); !s) return s;
    ++next_;
  }
}

}  // namespace rotolidar::sim
