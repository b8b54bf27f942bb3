#pragma once
// Dynamic objects (people, cars) of a scene: where they are at time t, and their bodies.
//
// Motion model: an object moves along its polyline at constant horizontal speed; its horizontal arc length at
// time t is s(t) = start_offset_m + speed_mps * t. A looped path wraps s modulo its closed length; an open path
// goes back and forth (period 2L). Its body frame B sits at the path point (z interpolated between the
// waypoints' ground heights), with x along the direction of travel and z up; the heading switches at the
// waypoints (no smoothing: the LiDAR and the camera only need where the surfaces are). Everything is a pure function of t (no state), so any consumer
// (EmbreeScene::SetTime, MujocoScene::SetTime) gets the same pose for the same t.
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/types/time.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {

/// Horizontal length of the object's path [m]: the closed polygon when `loop`, else the open polyline.
double PathLength(const DynamicObject& object);

/// T_world_body at time t (any t, also negative). The object must have >= 2 distinct waypoints.
Eigen::Isometry3d DynamicObjectPose(const DynamicObject& object, Seconds t);

/// The default body of a kind in its body frame, all parts with `material_id`:
///  - "person": legs, torso (boxes) and head (cylinder), 1.73 m tall, 0.46 m wide;
///  - "car": body and cabin (boxes) and 4 wheels (cylinders), 4.4 x 1.8 x 1.49 m.
/// Empty for any other kind.
std::vector<Primitive> DefaultBody(const std::string& kind, int material_id);

/// The object's triangles in its body frame B (primitive_ids index object.parts; materials = the scene's).
TriangleMesh BuildObjectMesh(const Scene& scene, const DynamicObject& object);

/// Checks name, kind, parts, path (>= 2 waypoints, length > 0), speed; false with the object named.
bool ValidateDynamicObject(const DynamicObject& object, const Scene& scene, std::string* error);

}  // namespace rotolidar::sim
