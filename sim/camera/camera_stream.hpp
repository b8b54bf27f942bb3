#pragma once
// The camera in the sim: CameraSimulator makes one frame (renderer + motion blur + sensor) at the true camera
// pose; CameraStream schedules frames along the physics trace as the LiDAR stream does, writes them into the
// recording (camera.csv + camera/%06d.png through RecordingWriter) and the true camera pose into truth/cam.tum.
//
// Timing: frame k is exposed around t_k = (k + 0.5) / rate_hz (its mid-exposure time, the time camera.csv and
// cam.tum carry). Row v (rolling shutter) is exposed around t_k + (v / (height - 1) - 0.5) * readout_s, each row for
// exposure_s. A frame needs the true pose over [t_k - half_span, t_k + half_span], half_span = (exposure_s +
// readout_s) / 2 <= half a frame period (CameraConfig::Validate).
//
// Thread safety: not thread-safe; rendering uses config.threads worker threads internally. With the Embree
// renderer, the EmbreeScene is shared with the LiDAR: its SetTime is called per frame (call between packets).
#include <cstdint>
#include <functional>
#include <memory>

#include <opencv2/core.hpp>

#include "core/io/recording.hpp"
#include "core/types/geometry.hpp"
#include "core/types/time.hpp"
#include "sim/camera/camera_model.hpp"
#include "sim/camera/camera_renderer.hpp"
#include "sim/camera/image_effects.hpp"
#include "sim/rig/rig_trace.hpp"
#include "sim/sensors/sensor_clock.hpp"
#include "sim/truth/truth.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {

/// The true T_world_cam at time t [s].
using CameraPoseFn = std::function<Pose3(Seconds)>;

/// Wall time of each stage of one frame [s].
struct CameraFrameStats {
  double render_s = 0.0;  ///< the renderer (all subframes)
  double blur_s = 0.0;    ///< velocity blur
  double sensor_s = 0.0;  ///< exposure, noise, quantisation
  double blur_px = 0.0;   ///< velocity blur: the largest half-length of a pixel's blur path [px]
};

class CameraSimulator {
 public:
  /// Builds the configured renderer for `scene`. `embree` (built from `scene`, outliving the simulator) is
  /// required for the Embree renderer and unused by OSMesa. Fails naming the field or the engine's error.
  static Status Create(const CameraConfig& config, uint64_t run_seed, const Scene& scene, EmbreeScene* embree,
                       std::unique_ptr<CameraSimulator>* out);

  /// Renders frame `index` exposed around t_mid_s with the camera at T_world_cam_at (called for times within
  /// half_span_s() of t_mid_s) into *bgr8 (CV_8UC3). The noise depends only on (run seed, index).
  Status RenderFrame(long index, Seconds t_mid_s, const CameraPoseFn& T_world_cam_at, cv::Mat* bgr8,
                     CameraFrameStats* stats = nullptr);

  /// The last frame's radiance before the sensor (after motion blur); depth_m: the mid-exposure render's.
  const RadianceImage& last_radiance() const { return blurred_; }
  const PixelRayTable& rays() const { return rays_; }
  const CameraConfig& config() const { return config_; }
  double half_span_s() const { return 0.5 * (config_.exposure_s + config_.readout_s); }

 private:
  CameraSimulator() = default;
  /// The renderer's image at exposure offset dt_s from mid-exposure (one pose per row with rolling shutter).
  Status RenderAt(Seconds t_mid_s, double dt_s, const CameraPoseFn& T_world_cam_at, RadianceImage* out);

  CameraConfig config_;
  uint64_t run_seed_ = 0;
  PixelRayTable rays_;
  std::unique_ptr<CameraRenderer> renderer_;
  RadianceImage sharp_, blurred_, sub_;
  std::vector<Pose3> row_poses_;
};

/// The camera's frames along the physics trace (the LidarStream's counterpart in sim_runner.cpp).
class CameraStream {
 public:
  /// `clock` stamps the frames written (camera.csv); cam.tum keeps the true rig time.
  CameraStream(std::unique_ptr<CameraSimulator> camera, const Pose3& T_base_cam, const SensorClock& clock = {})
      : camera_(std::move(camera)), T_base_cam_(T_base_cam), clock_(clock) {}

  /// Renders, writes (image + camera.csv row + cam.tum line) every frame whose exposure lies within the trace
  /// and ends by duration_s. Fails with the writer's message.
  Status RenderCovered(const RigTrace& trace, Seconds duration_s, RecordingWriter* writer, TruthWriter* truth);
  /// The earliest time the next frame will ask the trace for (drop trace samples before it only).
  Seconds NextNeededTime() const { return FrameTime(next_) - camera_->half_span_s(); }
  Seconds FrameTime(long k) const { return (static_cast<double>(k) + 0.5) / camera_->config().rate_hz; }
  long frames() const { return next_; }
  const CameraFrameStats& total_stats() const { return total_; }

 private:
  std::unique_ptr<CameraSimulator> camera_;
  Pose3 T_base_cam_;
  SensorClock clock_;  // stamps camera.csv
  long next_ = 0;
  cv::Mat image_;
  CameraFrameStats total_;
};

}  // namespace rotolidar::sim
