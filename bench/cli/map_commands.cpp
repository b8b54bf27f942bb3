// `rotolidar mapeval`: map metrics against a scene's truth (bench/metrics/map_metrics.hpp).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/metrics/map_metrics.hpp"
#include "bench/run/progress.hpp"
#include "core/io/trajectory_io.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::bench {
namespace {

// "xmin,ymin,zmin,xmax,ymax,zmax" -> box; "" -> empty box.
Status ParseRegion(const std::string& text, Eigen::AlignedBox3d* box) {
  box->setEmpty();
  if (text.empty()) return Status::Ok();
  std::stringstream ss(text);
  double v[6];
  char comma = ',';
  for (int i = 0; i < 6; ++i)
    if (!(ss >> v[i]) || (i < 5 && !(ss >> comma)) || comma != ',')
      return Status::Error("mapeval: --region: expected xmin,ymin,zmin,xmax,ymax,zmax (m)");
  *box = Eigen::AlignedBox3d(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
  if (box->isEmpty()) return Status::Error("mapeval: --region: min must not exceed max");
  return Status::Ok();
}

// Map points in the scene frame: as stored (no --estimate), or moved by the truth/estimate alignment.
Status LoadMap(const OptionParser& p, const Trajectory& truth, std::vector<Eigen::Vector3f>* map_world,
               std::string* how) {
  Eigen::Isometry3d T_scene_map = Eigen::Isometry3d::Identity();
  *how = "as stored (already in the scene frame)";
  if (!p.Get("estimate").empty()) {
    if (truth.empty()) return Status::Error("mapeval: --estimate needs --truth");
    MapAlignment alignment;
    if (!ParseMapAlignment(p.Get("align"), &alignment)) return Status::Error("mapeval: --align: first or se3");
    Trajectory estimate;
    if (Status s = ReadTrajectory(p.Get("estimate"), TrajectoryFormat::kTum, &estimate); !s) return s;
    if (Status s = MapToSceneTransform(truth, estimate, alignment, &T_scene_map); !s) return s;
    *how = alignment == MapAlignment::kFirstPose ? "truth pose at the estimate's first stamp"
                                                 : "SE(3) Umeyama of the estimated onto the true positions";
  }
  return LoadMapInSceneFrame(p.Get("MAP"), T_scene_map, map_world);
}

Status ParseConfig(const OptionParser& p, const Trajectory& truth, MapMetricsConfig* c) {
  for (const Status& s : {p.GetDouble("distance", &c->coverage_distance_m), p.GetDouble("spacing", &c->sample_spacing_m),
                          p.GetDouble("cell", &c->density_cell_m), p.GetDouble("max-range", &c->visibility_max_range_m)})
    if (!s) return s;
  if (Status s = ParseRegion(p.Get("region"), &c->region); !s) return s;
  if (!p.Flag("no-visibility"))
    for (const StampedPose& pose : truth) c->viewpoints_world.push_back(pose.T_ref_body.translation());
  std::string why;
  if (!c->Validate(&why)) return Status::Error("mapeval: " + why);
  return Status::Ok();
}

}  // namespace

int CmdMapEval(int argc, char** argv) {
  OptionParser p("mapeval", "Map metrics against a scene's truth: coverage per surface class, density uniformity, "
                            "map-to-truth distance, measured vs true door/window/column sizes (docs/metrics.md).");
  p.AddPositional("MAP", "map file (.ply or .pcd), points in metres");
  p.Add("scene", "", "-", "scene name in scenes/ or a scene file (required)");
  p.Add("distance", "0.05", "m", "coverage distance: a surface sample is covered by a map point this close");
  p.Add("spacing", "0.05", "m", "surface sample grid spacing");
  p.Add("cell", "0.5", "m", "density cell edge");
  p.Add("region", "", "m", "only surfaces in xmin,ymin,zmin,xmax,ymax,zmax [scene frame] (default: all)");
  p.Add("truth", "", "-", "true base trajectory (TUM, scene frame): viewpoints for completeness");
  p.Add("estimate", "", "-", "the SLAM trajectory (TUM) of the map: with --truth, moves the map into the scene frame");
  p.Add("align", "first", "-", "first (truth pose at the first scan) | se3 (Umeyama over the trajectory)");
  p.Add("max-range", "30", "m", "visibility: farthest viewpoint that counts");
  p.AddFlag("no-visibility", "do not compute completeness even with --truth");
  p.Add("json", "", "-", "write the metrics as JSON (the \"map\" object) to this file");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  if (p.Get("scene").empty()) return Usage("mapeval: --scene is required");
  sim::Scene scene;
  if (Status s = sim::LoadScene(sim::ResolveScenePath(p.Get("scene")), &scene); !s) return Fail(s);
  Trajectory truth;
  if (!p.Get("truth").empty())
    if (Status s = ReadTrajectory(p.Get("truth"), TrajectoryFormat::kTum, &truth); !s) return Fail(s);
  MapMetricsConfig config;
  if (Status s = ParseConfig(p, truth, &config); !s) return Usage(s.message);
  std::vector<Eigen::Vector3f> map_world;
  std::string how;
  if (Status s = LoadMap(p, truth, &map_world, &how); !s) return Fail(s);
  config.keep_samples = false;
  config.keep_per_point = false;
  MapMetrics metrics;
  if (Status s = ComputeMapMetrics(scene, map_world, config, &metrics, MakeProgressPrinter("visibility")); !s)
    return Fail(s);
  std::cout << "scene " << scene.name << "; map frame: " << how << "\n";
  PrintMapMetrics(metrics, std::cout);
  if (!p.Get("json").empty()) {
    nlohmann::json j;
    ToJson(metrics, &j);
    std::ofstream file(p.Get("json"));
    file << nlohmann::json{{"map", j}}.dump(2) << "\n";
    if (!file) return Fail(Status::Error(p.Get("json") + ": write failed"));
  }
  return 0;
}

}  // namespace rotolidar::bench
