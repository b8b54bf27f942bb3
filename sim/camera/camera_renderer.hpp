#pragma once
// The interface both camera renderers implement (Embree ray casting: embree_camera.hpp; MuJoCo + OSMesa:
// osmesa_camera.hpp). A renderer produces linear radiance and depth; the sensor (image_effects.hpp) makes bytes.
#include <vector>

#include "core/types/geometry.hpp"
#include "core/types/time.hpp"
#include "core/util/status.hpp"
#include "sim/camera/image_effects.hpp"

namespace rotolidar::sim {

class CameraRenderer {
 public:
  virtual ~CameraRenderer() = default;
  /// Renders the scene with its dynamic objects posed at time t_s, seen from T_world_cam_rows (optical frame):
  /// one pose for every row (global shutter) or exactly `height` poses, row v exposed at pose v (rolling
  /// shutter). Fills out's radiance and depth at the configured size. Fails naming the renderer on engine errors
  /// or a pose list of the wrong size. Not thread-safe (it moves the scene's dynamic objects).
  virtual Status Render(Seconds t_s, const std::vector<Pose3>& T_world_cam_rows, RadianceImage* out) = 0;
  virtual const char* name() const = 0;
};

}  // namespace rotolidar::sim
