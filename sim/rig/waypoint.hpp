#pragma once
// A waypoint of a carrier's default path, in the world frame (z up). Scenes (sim/world) list them per carrier
// type; carrier paths (sim/rig/carrier_paths) follow them. Kept in its own header so neither depends on the other.
namespace rotolidar::sim {

struct Waypoint2d {
  double x_m = 0.0;      ///< world x [m]
  double y_m = 0.0;      ///< world y [m]
  double dwell_s = 0.0;  ///< pause at this waypoint before moving on [s] (>= 0)
};

}  // namespace rotolidar::sim
