// `rotolidar kitti-twin --seq NN --out DIR`: a simulated KITTI odometry sequence (docs/kitti.md, "KITTI twin").
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/run/kitti_twin.hpp"
#include "bench/run/progress.hpp"
#include "sim/realism.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::bench {
namespace {

int TwinFail(const Status& s) {
  std::cerr << "error: kitti-twin: " << s.message << "\n";
  return 1;
}

/// $ROTOLIDAR_DATA/kitti_poses/<seq>.txt when the variable is set, else "".
std::string DefaultPoses(const std::string& seq) {
  const char* root = std::getenv("ROTOLIDAR_DATA");
  return root && *root ? std::string(root) + "/kitti_poses/" + seq + ".txt" : "";
}

Status ReadTwinOptions(const OptionParser& p, KittiTwinOptions* o) {
  o->sequence = p.Get("seq");
  o->out_dir = p.Get("out");
  o->poses_path = p.Get("poses").empty() ? DefaultPoses(o->sequence) : p.Get("poses");
  o->scene = p.Get("scene").empty() ? KittiTwinDefaultScene(o->sequence) : p.Get("scene");
  // The realism preset first (what KITTI's published bins carry), then the explicit flags.
  sim::Realism realism = sim::Realism::kTypical;
  if (Status s = sim::RealismFromWord(p.Get("realism"), &realism); !s) return Status::Error("--realism: " + s.message);
  o->motion_compensate = realism != sim::Realism::kHarsh || p.Flag("compensate");
  o->lidar.elevation_error_deg = realism == sim::Realism::kIdeal ? 0.0 : kKittiElevationErrorDeg;
  o->imu = sim::PresetSimConfig(realism).imu;  // the rig IMU's noise and the preset's sensor errors
  o->write_imu = !p.Flag("no-imu");
  long frames = 0, seed = 0, firings = 0;
  if (Status s = p.GetInt("frames", &frames); !s) return s;
  if (Status s = p.GetInt("seed", &seed); !s) return s;
  if (Status s = p.GetInt("firings", &firings); !s) return s;
  if (seed < 0) return Status::Error("--seed must be >= 0");
  o->frames = int(frames);
  o->seed = uint64_t(seed);
  o->lidar.firings_per_revolution = int(firings);
  if (Status s = p.GetDouble("range-sigma", &o->lidar.range_noise_sigma_m); !s) return s;
  if (p.IsSet("elevation-error"))
    if (Status s = p.GetDouble("elevation-error", &o->lidar.elevation_error_deg); !s) return s;
  if (o->poses_path.empty())
    return Status::Error("--poses is required (or set ROTOLIDAR_DATA to find kitti_poses/" + o->sequence + ".txt)");
  if (o->scene.empty())
    return Status::Error("sequence " + o->sequence + " has no committed scene: generate one with "
                         "`python3 scenes/generators/make_urban_loop.py POSES --name kitti_" + o->sequence +
                         " --out-dir DIR` and pass --scene DIR/kitti_" + o->sequence + ".yaml");
  std::string error;
  if (!o->Validate(&error)) return Status::Error(error);
  return Status::Ok();
}

}  // namespace

int CmdKittiTwin(int argc, char** argv) {
  const KittiTwinOptions defaults;
  OptionParser p("kitti-twin", "Simulate KITTI's HDL-64E car on a KITTI ground-truth path through a generated street "
                               "scene and write it as a KITTI odometry sequence: velodyne/ bins (motion-"
                               "compensated with the true poses except under --realism harsh), velodyne_times/, "
                               "poses.txt, times.txt, calib.txt, sequence_info.txt, imu.csv, "
                               "calib_imu_to_velo.txt; read it with `slam --kitti DIR` (docs/kitti.md).");
  p.Add("seq", defaults.sequence, "-", "KITTI sequence (07 has the committed scene urban_loop)");
  p.Add("out", "", "-", "output sequence folder (required)");
  p.Add("frames", "0", "-", "frames from frame 0 (0 = all the poses cover)");
  p.Add("seed", "1", "-", "run seed (range noise)");
  p.Add("poses", "", "-", "ground-truth poses (default $ROTOLIDAR_DATA/kitti_poses/<seq>.txt)");
  p.Add("scene", "", "-", "scene name or file in the generator's frame (default: urban_loop for 07)");
  p.Add("range-sigma", std::to_string(defaults.lidar.range_noise_sigma_m), "m", "range noise, 1 sigma");
  p.Add("realism", "typical", "-",
        "ideal: bins compensated with the true poses, exact angles | typical: as KITTI's published bins, also "
        "with their 0.22 deg vertical-angle error | harsh: typical, not motion-compensated");
  p.Add("elevation-error", "(preset)", "deg", "intrinsic vertical-angle error of every reported point (overrides "
        "the preset's)");
  p.Add("firings", std::to_string(defaults.lidar.firings_per_revolution), "-", "firing columns per revolution");
  p.AddFlag("no-imu", "write no imu.csv / calib_imu_to_velo.txt (an IMU-less sequence, as KITTI's odometry set)");
  p.AddFlag("compensate", "motion-compensate the bins with the true poses even under --realism harsh");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  KittiTwinOptions o;
  if (p.Get("out").empty()) {
    std::cerr << "error: kitti-twin: --out DIR is required (see --help)\n";
    return 2;
  }
  if (Status s = ReadTwinOptions(p, &o); !s) return TwinFail(s);
  KittiTwinResult r;
  if (Status s = RunKittiTwin(o, &r, MakeProgressPrinter("kitti-twin")); !s) return TwinFail(s);
  std::printf("wrote %s: %zu frames (%.1f m of path), %zu points (%.0f a frame), %zu IMU samples, scene %s, %s; "
              "casting %.1f s (%.0f ms a frame)\n", o.out_dir.c_str(), r.frames, r.path_length_m, r.points,
              double(r.points) / double(r.frames), r.imu_samples, r.scene_path.c_str(),
              o.motion_compensate ? "motion-compensated with the true poses" : "not motion-compensated",
              r.cast_s, 1e3 * r.cast_s / double(r.frames));
  return 0;
}

}  // namespace rotolidar::bench
