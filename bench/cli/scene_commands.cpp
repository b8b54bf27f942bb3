// `rotolidar scene list|show`: thin wrappers around bench/scene/scene_show.hpp.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/scene/scene_show.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::bench {
namespace {

/// The folder sim::ResolveScenePath looks names up in ($ROTOLIDAR_SCENES, else the source tree's scenes/): the
/// empty name is never an existing file, so it resolves to "<dir>/.yaml".
std::string DefaultSceneDir() { return std::filesystem::path(sim::ResolveScenePath("")).parent_path().string(); }

int SceneList(int argc, char** argv) {
  OptionParser p("scene list", "List the scene files of a folder: triangles (static, dynamic), extent, dynamic "
                               "objects, load time, BVH build time, median EmbreeScene::SetTime (move us).");
  p.Add("dir", DefaultSceneDir(), "-", "folder of scene files (*.yaml)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  std::vector<SceneInfo> infos;
  if (Status s = ListScenes(p.Get("dir"), &infos); !s) return Fail(s);
  std::printf("%-14s %9s %8s %6s %-24s %7s %8s %8s %8s  %s\n", "scene", "triangles", "dynamic", "closed",
              "extent x*y*z [m]", "objects", "load ms", "bvh ms", "move us", "carriers");
  int failures = 0;
  for (const SceneInfo& i : infos) {
    if (!i.ok) {
      std::printf("%-14s ERROR %s\n", i.name.c_str(), i.error.c_str());
      ++failures;
      continue;
    }
    const Eigen::Vector3d e = i.extent.sizes();
    char extent[64];
    std::snprintf(extent, sizeof(extent), "%.1f x %.1f x %.1f", e.x(), e.y(), e.z());
    std::string carriers;
    for (const std::string& c : i.carriers) carriers += (carriers.empty() ? "" : ",") + c;
    std::printf("%-14s %9zu %8zu %6s %-24s %7zu %8.1f %8.1f %8.1f  %s\n", i.name.c_str(), i.static_triangles,
                i.dynamic_triangles, i.closed ? "yes" : "no", extent, i.dynamic_objects, i.load_ms, i.embree_ms,
                i.set_time_us, carriers.c_str());
  }
  return failures ? 1 : 0;
}

int SceneShow(int argc, char** argv) {
  SceneShowOptions o;
  OptionParser p("scene show", "Render a scene's top and perspective views (PNG) and write its element truth (CSV).");
  p.AddPositional("scene", "scene name in scenes/ or a scene file path");
  p.Add("out", o.out_dir, "-", "output folder");
  p.Add("width", std::to_string(o.width_px), "px", "image width");
  p.Add("height", std::to_string(o.height_px), "px", "image height");
  p.Add("time", "0", "s", "scene time at which dynamic objects are drawn");
  p.Add("samples", std::to_string(o.multisamples), "-", "multisampling (anti-aliasing) samples, 0..16");
  p.Add("bits", std::to_string(o.color_bits), "-", "bits kept per colour channel in the PNGs, 1..8 (smaller files)");
  p.AddFlag("shadows", "draw shadows (slower)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  long width = 0, height = 0, samples = 0, bits = 0;
  if (Status s = p.GetInt("width", &width); !s) return Fail(s);
  if (Status s = p.GetInt("height", &height); !s) return Fail(s);
  if (Status s = p.GetInt("samples", &samples); !s) return Fail(s);
  if (Status s = p.GetInt("bits", &bits); !s) return Fail(s);
  if (bits < 1 || bits > 8) return Fail(Status::Error("--bits must be in 1..8"));
  if (Status s = p.GetDouble("time", &o.time_s); !s) return Fail(s);
  o.out_dir = p.Get("out");
  o.width_px = static_cast<int>(width);
  o.height_px = static_cast<int>(height);
  o.multisamples = static_cast<int>(samples);
  o.color_bits = static_cast<int>(bits);
  o.shadows = p.Flag("shadows");
  SceneShowResult r;
  if (Status s = ShowScene(p.Get("scene"), o, &r); !s) return Fail(s);
  std::printf("wrote %s\nwrote %s\nwrote %s\n(rendered in %.0f ms)\n", r.top_png.c_str(), r.perspective_png.c_str(),
              r.elements_csv.c_str(), r.render_ms);
  return 0;
}

void PrintSceneUsage(std::ostream& os) {
  os << "usage: rotolidar scene <list|show> [options]   (rotolidar scene <sub> --help)\n"
     << "  list            scenes in scenes/ with triangles, extent, dynamic objects, load time\n"
     << "  show NAME       top and perspective PNGs and the element truth CSV of one scene\n";
}

}  // namespace

int CmdScene(int argc, char** argv) {
  if (argc < 1 || std::string(argv[0]) == "--help" || std::string(argv[0]) == "-h") {
    PrintSceneUsage(argc < 1 ? std::cerr : std::cout);
    return argc < 1 ? 2 : 0;
  }
  const std::string sub = argv[0];
  if (sub == "list") return SceneList(argc - 1, argv + 1);
  if (sub == "show") return SceneShow(argc - 1, argv + 1);
  std::cerr << "error: unknown scene subcommand '" << sub << "'\n";
  PrintSceneUsage(std::cerr);
  return 2;
}

}  // namespace rotolidar::bench
