#pragma once
// The carrier of a run as the scene sees it: which carrier a scene offers, which one a run gets when the user
// names only the scene, the scene's default path filled into the carrier, and the check that the carrier's
// target path stays inside the scene's bounds and clear of its static geometry before anything is simulated.
//
// Default carrier of a scene (ChooseSceneCarrier): its `handheld` path if it has one, else its first listed
// path, else the scripted loop (sim/rig/base_motion.hpp) -- which the caller then checks with CheckCarrierPath,
// since the loop's room need not be the scene's.
//
// Path check (CheckCarrierPath): the target path (BaseMotion, what the physics body tracks within millimetres)
// is sampled over [0, duration] every 20 ms (at most 200,000 samples); every sample must lie in Scene::bounds
// and the straight segment between consecutive samples must not cross a static triangle (one Embree ray per
// segment; dynamic objects are ignored: they move out of the way; a dip of less than 5 cm into an obstacle is
// a graze, let through: PathCheckOptions::graze_m). Errors name the carrier, the time, the
// point, the bound or the static primitive, and the waypoint leg the point lies on (index and coordinates).
// Cost: one ray per segment (docs/scenes.md, 'Simulating in a scene').
#include <string>
#include <vector>

#include "core/util/status.hpp"
#include "sim/rig/carrier_paths.hpp"
#include "sim/world/embree_scene.hpp"
#include "sim/world/scene.hpp"

namespace rotolidar::sim {

/// Carriers with a default path in the scene ("handheld", "wheeled", "car"), in the scene file's order.
std::vector<std::string> SceneCarriers(const Scene& scene);

/// Sets carrier->type to the scene's default carrier (see the file comment); leaves the type's parameters.
void ChooseSceneCarrier(const Scene& scene, CarrierConfig* carrier);

/// Fills an empty handheld / wheeled / car path from the scene's default path for that carrier. Fails, naming
/// the scene and the carriers it offers, when the active carrier needs a scene path the scene lacks.
Status FillScenePath(const Scene& scene, CarrierConfig* carrier);

struct PathCheckOptions {
  double sample_dt_s = 0.02;      ///< spacing of the path samples [s]
  size_t max_samples = 200000;    ///< longer runs sample coarser (duration / max_samples)
  /// A path that dips less than this into an obstacle and comes out again is let through: the path moved this
  /// far along the hit surface's normal is clear within graze_window_s of the hit [m]; <= 0: no grazes. A crossing
  /// of a wall or pane is never a graze. Default 5 cm: the demo's scripted loop through the box room grazes a
  /// column and its recording must not change (why: docs/scenes.md, 'Simulating in a scene').
  double graze_m = 0.05;
  double graze_window_s = 1.0;    ///< half width of the stretch of path moved for the graze test [s]
};

/// Checks `motion` (the carrier `carrier` describes) over [0, duration_s] against the scene's bounds and its
/// static geometry in `embree` (built from `scene`). Ok, or an error naming what is hit where (file comment).
Status CheckCarrierPath(const CarrierConfig& carrier, const BaseMotion& motion, double duration_s,
                        const Scene& scene, const EmbreeScene& embree, const PathCheckOptions& options = {});

}  // namespace rotolidar::sim
