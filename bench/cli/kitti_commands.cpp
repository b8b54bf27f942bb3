// `rotolidar slam --kitti DIR` and `rotolidar export RECORDING --kitti OUT` (docs/kitti.md).
#include <cstdio>
#include <iostream>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/run/kitti_export.hpp"
#include "bench/run/kitti_run.hpp"
#include "bench/run/progress.hpp"
#include "core/pipeline/estimator_config_yaml.hpp"
#include "core/io/yaml_util.hpp"

namespace rotolidar::bench {
namespace {

Status LoadEstimatorConfig(const std::string& path, EstimatorConfig* config) {
  if (path.empty()) return Status::Ok();
  try {
    return ParseEstimatorConfig(path, yaml::LoadFile(path), config);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
}

Status GetCount(const OptionParser& p, const std::string& name, int* value) {
  long v = 0;
  if (Status s = p.GetInt(name, &v); !s) return s;
  if (v < 0) return Status::Error("--" + name + " must be >= 0 (got " + std::to_string(v) + ")");
  *value = int(v);
  return Status::Ok();
}

void PrintStats(const char* name, const EvalResult& e, const char* unit) {
  if (!e.status) {
    std::printf("  %-28s n/a (%s)\n", name, e.status.message.c_str());
    return;
  }
  std::printf("  %-28s rmse %.4f  mean %.4f  median %.4f  max %.4f %s (%zu)\n", name, e.stats.rmse, e.stats.mean,
              e.stats.median, e.stats.max, unit, e.stats.count);
}

}  // namespace

int CmdSlamKitti(int argc, char** argv) {
  KittiRunOptions o;
  OptionParser p("slam --kitti", "Run the SLAM core on a KITTI odometry sequence (base = velodyne), LiDAR-"
                                 "inertial when it has imu.csv + calib_imu_to_velo.txt, else LiDAR-only; "
                                 "trajectory in KITTI's cam0 convention, map, per-frame table, metrics vs the "
                                 "ground truth when a poses file is found (docs/kitti.md).");
  p.Add("kitti", "", "-", "sequence folder holding velodyne/%06d.bin (and calib.txt, times.txt)");
  p.Add("out", o.out_dir, "-", "output folder");
  p.Add("frames", "0", "-", "at most this many frames (0 = all)");
  p.Add("start", "0", "-", "first frame id");
  p.Add("calib", "", "-", "calib.txt (default DIR/calib.txt)");
  p.Add("times", "", "-", "times.txt (default DIR/times.txt; none: nominal 10 Hz)");
  p.Add("poses", "", "-", "reference poses, e.g. ground truth (default DIR/poses.txt or DIR/../../poses/<DIR name>.txt)");
  p.Add("config", "", "-", "estimator config YAML (keys of slam_config.yaml) over the KITTI defaults");
  p.Add("lines", "0", "-", "scan lines per frame (0: DIR/sequence_info.txt's scan_lines, else the first frame's)");
  p.Add("imu", "auto", "-", "auto: use DIR/imu.csv when present | on: require it | off: LiDAR-only");
  p.Add("deskew", "auto", "-", "auto: deskew raw bins (sequence_info.txt's deskew: none...) | on | off");
  p.AddFlag("strict", "fail on missing frame ids or empty bins instead of warning");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  if (!ParseKittiSwitch(p.Get("deskew"), &o.deskew)) return Fail(Status::Error("--deskew: auto, on or off"));
  o.paths.dir = p.Get("kitti");
  o.paths.calib_path = p.Get("calib");
  o.paths.times_path = p.Get("times");
  o.paths.poses_path = p.Get("poses");
  if (!ParseKittiSwitch(p.Get("imu"), &o.imu)) return Fail(Status::Error("--imu: auto, on or off"));
  o.out_dir = p.Get("out");
  if (Status s = GetCount(p, "frames", &o.max_frames); !s) return Fail(s);
  if (Status s = GetCount(p, "start", &o.start_frame); !s) return Fail(s);
  if (Status s = GetCount(p, "lines", &o.scan.expected_lines); !s) return Fail(s);
  if (Status s = LoadEstimatorConfig(p.Get("config"), &o.estimator); !s) return Fail(s);
  o.strict = p.Flag("strict");
  KittiRunResult r;
  if (Status s = RunKitti(o, &r, MakeProgressPrinter("slam")); !s) return Fail(s);
  for (const InputWarning& w : r.input_warnings) std::printf("warning: %s\n", w.message.c_str());
  std::printf("%zu frames (%d..%d), median %.1f ms per frame, map %zu points; outputs in %s\n", r.frame_ids.size(),
              r.frame_ids.front(), r.frame_ids.back(), r.median_scan_ms, r.map_points, o.out_dir.c_str());
  std::printf("scan lines: %d expected (from %s), split by %s; range noise %.3g m (from %s)\n", r.expected_lines,
              r.expected_lines_source.c_str(), r.point_times ? "the per-point times (velodyne_times/)" : "azimuth",
              r.range_sigma_m, r.range_sigma_source.c_str());
  if (r.frames_other_line_count > 0 || r.elevation_inversions > 0)
    std::printf("warning: %zu frames without %d scan lines, %zu elevation inversions (rings may be off)\n",
                r.frames_other_line_count, r.expected_lines, r.elevation_inversions);
  std::printf("%s\n", r.imu_used ? ("LiDAR-inertial: " + std::to_string(r.imu_samples_fed) + " IMU samples, " +
                                      std::to_string(r.frames_imu_initialized) + " frames from the sliding window")
                                         .c_str()
                                   : "LiDAR-only (no IMU used)");
  PrintScanHealth(r.scans);
  std::printf("deskew: %s\n", r.deskewed ? "by the estimator from the per-point times" : "none (compensated bins)");
  if (r.nominal_times) std::printf("note: no times file: nominal 10 Hz frame times\n");
  if (r.loop_closure) PrintLoopClosure(r.loops);
  if (r.has_ground_truth) {
    std::printf("vs %s (cam0 convention, rebased to frame %d):\n", r.poses_path.c_str(), r.frame_ids.front());
    PrintStats("APE translation (no align)", r.ape, "m");
    PrintStats("APE translation (SE(3))", r.ape_se3, "m");
    if (r.loop_closure) {
      PrintStats("APE odometry (no align)", r.ape_odometry, "m");
      PrintStats("APE odometry (SE(3))", r.ape_se3_odometry, "m");
    }
    PrintStats("RPE translation (1 frame)", r.rpe_translation, "m");
    PrintStats("RPE rotation (1 frame)", r.rpe_rotation, "deg");
  }
  return 0;
}

int CmdExport(int argc, char** argv) {
  KittiExportOptions o;
  OptionParser p("export", "Write a recording as a KITTI odometry sequence: one velodyne bin per VLP-16 revolution "
                           "(deskewed into the base frame at the revolution start) with per-point times, times.txt, "
                           "calib.txt, sequence_info.txt and, with truth, poses (docs/kitti.md).");
  p.AddPositional("RECORDING", "recording folder (docs/recording_format.md)");
  p.Add("kitti", "", "-", "output dataset root: sequences/<seq>/..., poses/<seq>.txt (required)");
  p.Add("sequence", o.sequence, "-", "sequence name");
  p.Add("return", "strongest", "-", "dual-return recordings: strongest|last");
  p.Add("deskew", "estimator", "-", "estimator (the core's own deskew) | truth (simulated recordings only: exact)");
  p.Add("config", "", "-", "estimator config YAML (estimator deskew only)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  if (p.Get("kitti").empty()) {
    std::cerr << "error: export: --kitti OUT is required (see --help)\n";
    return 2;
  }
  o.recording_dir = p.Get("RECORDING");
  o.out_dir = p.Get("kitti");
  o.sequence = p.Get("sequence");
  if (p.Get("return") == "strongest") o.return_filter = Vlp16ReturnFilter::kStrongest;
  else if (p.Get("return") == "last") o.return_filter = Vlp16ReturnFilter::kLast;
  else return Fail(Status::Error("--return: strongest or last (got '" + p.Get("return") + "')"));
  if (!ParseKittiDeskewSource(p.Get("deskew"), &o.deskew))
    return Fail(Status::Error("--deskew: estimator or truth (got '" + p.Get("deskew") + "'" +
                              (p.Get("deskew") == "auto" ? ": 'auto' picked the simulation's truth by itself" : "") +
                              ")"));
  if (Status s = LoadEstimatorConfig(p.Get("config"), &o.estimator); !s) return Fail(s);
  KittiExportResult r;
  if (Status s = ExportKitti(o, &r, MakeProgressPrinter("export")); !s) return Fail(s);
  std::printf("wrote %s: %zu frames, %zu points (%zu skipped), poses %s\n", r.sequence_dir.c_str(), r.frames,
              r.points, r.points_skipped, r.wrote_poses ? "from the truth" : "none (no truth)");
  std::printf("deskew: %s (stated in %s)\n", KittiDeskewDescription(r.deskew).c_str(), r.info_path.c_str());
  return 0;
}

}  // namespace rotolidar::bench
