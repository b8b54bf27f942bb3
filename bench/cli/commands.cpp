// demo, sim and slam: the pipeline commands.
#include "bench/cli/commands.hpp"

#include <cstdio>
#include <filesystem>
#include <iostream>

#include <yaml-cpp/yaml.h>

#include "bench/cli/options.hpp"
#include "bench/cli/signals.hpp"
#include "bench/demo/demo.hpp"
#include "bench/report/run_report.hpp"
#include "bench/run/progress.hpp"
#include "bench/run/scan_health.hpp"
#include "bench/run/truth_eval.hpp"
#include "core/pipeline/estimator_config_yaml.hpp"
#include "core/io/yaml_fields.hpp"
#include "core/io/yaml_util.hpp"
#include "sim/sim_runner.hpp"

namespace rotolidar::bench {

Status LoadSlamConfig(const std::string& path, EstimatorConfig* config) {
  if (path.empty()) return Status::Ok();
  try {
    return ParseEstimatorConfig(path, yaml::LoadFile(path), config);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
}

namespace {

/// --carrier: scene (the scene's default), handheld, wheeled, car or scripted_loop.
Status ApplyCarrierOption(const OptionParser& p, sim::SimConfig* config) {
  const std::string name = p.Get("carrier");
  sim::CarrierType type = sim::CarrierType::kScriptedLoop;
  if (name == "scene") {
    config->carrier_from_scene = true;
    return Status::Ok();
  }
  if (name == "kitti" || !sim::CarrierTypeFromName(name, &type))
    return Status::Error("--carrier: scene, handheld, wheeled, car or scripted_loop (got '" + name + "')");
  config->carrier.type = type;
  config->carrier_from_scene = false;
  return Status::Ok();
}

/// The sim config of `sim` and `demo`: the built-in default, then --config's keys, then the flags. The carrier
/// is the scene's default unless --carrier or the config file's carrier.type names one.
Status LoadSimOverrides(const OptionParser& p, sim::SimConfig* config) {
  config->carrier_from_scene = true;
  sim::Realism realism = sim::Realism::kTypical;
  if (Status s = sim::RealismFromWord(p.Get("realism"), &realism); !s) return Status::Error("--realism: " + s.message);
  sim::ApplyRealism(realism, config);
  if (!p.Get("config").empty())
    if (Status s = sim::LoadSimConfig(p.Get("config"), config); !s) return s;
  if (p.IsSet("realism") && config->realism != realism)  // the file named another preset: which one was meant?
    return Status::Error("--realism " + p.Get("realism") + " contradicts " + p.Get("config") + "'s realism: " +
                         yaml::EnumWord(config->realism));
  long seed = 0;
  if (p.IsSet("seed")) {
    if (Status s = p.GetInt("seed", &seed); !s) return s;
    config->seed = uint64_t(seed);
  }
  if (p.IsSet("duration"))
    if (Status s = p.GetDouble("duration", &config->duration_s); !s) return s;
  if (p.IsSet("scene")) config->scene = p.Get("scene");
  if (p.IsSet("carrier"))
    if (Status s = ApplyCarrierOption(p, config); !s) return s;
  if (p.IsSet("camera")) {
    if (p.Get("camera") != "on" && p.Get("camera") != "off") return Status::Error("--camera: on or off");
    config->camera.enabled = p.Get("camera") == "on";
  }
  if (p.IsSet("motor-speed"))
    if (Status s = p.GetDouble("motor-speed", &config->motor.profile.speed_radps); !s) return s;
  if (p.IsSet("profile") && !sim::ParseMotorProfileType(p.Get("profile"), &config->motor.profile.type))
    return Status::Error("--profile: constant, trapezoid, nodding or stop_and_go");
  if (p.IsSet("axis")) {
    bool known = false;
    for (sim::MotorAxis a : {sim::MotorAxis::kHorizontal, sim::MotorAxis::kVertical, sim::MotorAxis::kTilted})
      if (p.Get("axis") == sim::MotorAxisName(a)) config->rig_model.motor.axis = a, known = true;
    if (!known) return Status::Error("--axis: horizontal, vertical or tilted");
  }
  std::string why;
  if (!config->Validate(&why)) return Status::Error("sim config: " + why);
  return Status::Ok();
}

void AddSimOptions(OptionParser* p, const sim::SimConfig& d) {
  p->Add("config", "", "-", "sim config YAML; its keys override the built-in default and the realism preset");
  p->Add("realism", "typical", "-",
         "error sources preset: ideal|typical|harsh (docs/noise_models.md); ideal = no rig, clock or extra sensor "
         "errors");
  p->Add("scene", d.scene, "-", "scene name in scenes/ or a scene file path");
  p->Add("carrier", "scene", "-",
         "scene (the scene's handheld path, else its first path, else scripted_loop if it fits)|handheld|"
         "wheeled|car|scripted_loop");
  p->Add("camera", d.camera.enabled ? "on" : "off", "-", "RGB camera: on|off (off: a much faster sim)");
  p->Add("duration", std::to_string(int(d.duration_s)), "s", "simulated time");
  p->Add("seed", std::to_string(d.seed), "-", "run seed (every random stream derives from it)");
  p->Add("motor-speed", std::to_string(d.motor.profile.speed_radps), "rad/s", "rotor speed (the seed's 2.6)");
  p->Add("profile", sim::ToString(d.motor.profile.type), "-", "motor profile: constant|trapezoid|nodding|stop_and_go");
  p->Add("axis", sim::MotorAxisName(d.rig_model.motor.axis), "-", "motor axis: horizontal|vertical|tilted");
}

}  // namespace

void PrintLoopClosure(const graph::LoopClosureState& s) {
  size_t rejected = 0;
  for (const graph::LoopRecord& l : s.loops) rejected += l.rejected ? 1 : 0;
  if (s.keyframes_dropped > 0)
    std::printf("loop closure: %zu keyframes dropped (database full or a pose that is no rotation)\n",
                s.keyframes_dropped);
  std::printf("loop closure: %zu keyframes (%zu with an image), %zu loops (%zu rejected by the graph); %zu "
              "candidates, %zu verified by GICP in %.1f s; %zu graph solves, the longest %.3f s%s%s\n",
              s.keyframes.size(), s.visual_keyframes, s.loops.size(), rejected, s.candidates_proposed,
              s.candidates_checked,
              s.verify_time_s, s.graph_solves, s.max_solve_time_s, s.last_message.empty() ? "" : "; last problem: ",
              s.last_message.c_str());
}

void PrintScanHealth(const std::vector<ScanReport>& scans) {
  const ScanHealth h = AssessScanHealth(scans);
  if (h.stretches.empty()) return;
  constexpr size_t kMaxLines = 10;
  const Seconds t0 = scans.front().t_start_s;
  for (size_t i = 0; i < h.stretches.size() && i < kMaxLines; ++i)
    std::printf("warning: %s\n", FormatStretch(h.stretches[i], t0).c_str());
  if (h.stretches.size() > kMaxLines)
    std::printf("warning: ... and %zu more stretches (metrics.json: health.stretches)\n",
                h.stretches.size() - kMaxLines);
  std::printf("registration problems: %zu of %zu scans did not converge, %zu degenerate (report.html: "
              "\"Registration problems\")\n", h.not_converged, h.scans, h.degenerate);
}

int CmdDemo(int argc, char** argv) {
  DemoOptions options;
  OptionParser p("demo", "Simulate the rotary rig in the default scene, run the SLAM core, report the error vs truth.");
  p.Add("out", options.out_dir, "-", "output folder (recording/, slam/, metrics.json, report.html)");
  AddSimOptions(&p, options.sim);
  p.Add("slam-config", "", "-", "estimator config YAML (keys of slam_config.yaml)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  options.out_dir = p.Get("out");
  if (Status s = LoadSimOverrides(p, &options.sim); !s) return Fail(s);
  if (Status s = LoadSlamConfig(p.Get("slam-config"), &options.slam); !s) return Fail(s);
  DemoResult r;
  if (Status s = RunDemo(options, &r); !s) return Fail(s);
  const double rt = r.slam.wall_time_s > 0 ? r.slam.data_duration_s / r.slam.wall_time_s : 0.0;
  std::printf("\nrotolidar demo: %s, %.0f s simulated (seed %llu)\n", options.sim.scene.c_str(),
              r.sim.sim_duration_s, (unsigned long long)options.sim.seed);
  std::printf("  sim   : %zu VLP-16 packets, %zu returns, %.1f s wall\n", r.sim.lidar_packets, r.sim.lidar_returns,
              r.sim.wall_time_s);
  std::printf("  slam  : %zu scans, median %.1f ms per scan, %.1fx real time, map %zu points\n",
              r.slam.scans.size(), r.slam.median_scan_ms, rt, r.slam.map_points);
  PrintScanHealth(r.slam.scans);
  std::printf("  ATE   : RMSE %.4f m (mean %.4f, max %.4f) over %zu poses, SE(3) Umeyama alignment\n",
              r.ape.stats.rmse, r.ape.stats.mean, r.ape.stats.max, r.ape.num_associated);
  if (r.evaluation.has_map_metrics)
    std::printf("  map   : map-to-truth median %.4f m, coverage %.1f %%, element size RMSE %.3f m\n",
                r.evaluation.map.map_to_truth.median_m, 100 * r.evaluation.map.coverage.total.coverage,
                r.evaluation.map.element_summary.rmse_m);
  if (r.evaluation.has_dynamic && r.evaluation.dynamic.returns_seen > 0)
    std::printf("  %s\n", DynamicShareLine(r.evaluation.dynamic).c_str());
  if (r.evaluation.has_deskew)
    std::printf("  deskew: per-point error median %.4f m, p90 %.4f m over %zu points\n",
                r.evaluation.deskew.all.median_m, r.evaluation.deskew.all.p90_m, r.evaluation.deskew.all.count);
  std::printf("  output: %s (report.html)\n", std::filesystem::absolute(options.out_dir).c_str());
  return 0;
}

int CmdSim(int argc, char** argv) {
  sim::SimConfig config = sim::DefaultSimConfig();
  OptionParser p("sim", "Simulate the rig and write a recording folder (calib.yaml, lidar.pcap, imu.csv, "
                        "encoder.csv, truth/).");
  p.AddPositional("OUT_DIR", "recording folder to write");
  AddSimOptions(&p, config);
  p.AddFlag("force", "write into a non-empty OUT_DIR, replacing its previous recording");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  if (Status s = LoadSimOverrides(p, &config); !s) return Fail(s);
  if (Status s = sim::PrepareRecordingDir(p.Get("OUT_DIR"), p.Flag("force")); !s) return Fail(s);
  sim::SimSummary summary;
  StopOnSignals stop;  // Ctrl-C / SIGTERM: end the simulation there and close the files
  if (Status s = sim::RunSimulation(config, p.Get("OUT_DIR"), &summary, MakeProgressPrinter("sim"), &stop.flag());
      !s)
    return Fail(s);
  std::printf("wrote %s: %.1f s simulated in %.1f s wall (%.1fx real time), %zu packets, %zu IMU, %zu encoder\n",
              summary.recording_dir.c_str(), summary.sim_duration_s, summary.wall_time_s,
              summary.sim_duration_s / summary.wall_time_s, summary.lidar_packets, summary.imu_samples,
              summary.encoder_samples);
  if (summary.stopped) {
    std::fprintf(stderr, "sim: stopped by %s at %.2f s of %.2f s: the recording is valid but ends there\n",
                 stop.name(), summary.sim_duration_s, config.duration_s);
    return 128 + stop.signal();
  }
  return 0;
}

int CmdSlam(int argc, char** argv) {
  for (int i = 0; i < argc; ++i)  // a KITTI sequence instead of a recording: its own options (kitti_commands.cpp)
    if (std::string(argv[i]) == "--kitti" || std::string(argv[i]).rfind("--kitti=", 0) == 0)
      return CmdSlamKitti(argc, argv);
  OptionParser p("slam", "Run the SLAM core on a recording folder; writes trajectory (TUM, KITTI), map (PLY, PCD), "
                         "per-scan timings, the resolved config, metrics.json and report.html (with the ATE when "
                         "the recording has truth/). --score adds the map metrics against the scene.");
  p.AddPositional("RECORDING", "recording folder (docs/recording_format.md)");
  p.Add("out", "runs/slam", "-", "output folder");
  p.Add("config", "", "-", "estimator config YAML (keys of slam_config.yaml)");
  p.Add("kitti", "", "-", "a KITTI sequence folder instead of RECORDING (`slam --kitti DIR --help`)");
  p.AddFlag("score", "also score the map against the sim's scene (coverage, completeness, map-to-truth, "
                     "elements; minutes on long runs, as `rotolidar mapeval`)");
  p.AddFlag("save-keyframes", "with loop closure on: write the keyframe database (poses, thinned points) into "
                              "OUT/keyframes/ (~100 kB per keyframe)");
  p.AddFlag("strict", "fail on a degraded input (no IMU, IMU or encoder gaps, an encoder resolution that "
                      "disagrees with calib.yaml, a missing calibration pose, lost packets) instead of warning");
  p.AddFlag("loop-snapshots", "with loop closure on: after each loop correction write the corrected map and "
                              "trajectory so far into OUT/loop_snapshots/ (one dense map per loop)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  EstimatorConfig config;
  if (Status s = LoadSlamConfig(p.Get("config"), &config); !s) return Fail(s);
  SlamRunResult r;
  SlamRunOptions run;
  run.progress = MakeProgressPrinter("slam");
  run.save_keyframes = p.Flag("save-keyframes");
  StopOnSignals stop_on_signals;  // Ctrl-C / SIGTERM: finish what was fed, write the outputs, flag them partial
  run.stop = &stop_on_signals.flag();
  run.loop_snapshots = p.Flag("loop-snapshots");
  run.strict = p.Flag("strict");
  for (const char* flag : {"save-keyframes", "loop-snapshots"})
    if (p.Flag(flag) && !config.loop_closure.enabled)
      return Fail(Status::Error(std::string("--") + flag +
                                ": loop closure is off (loop_closure: {enabled: true} in --config)"));
  if (Status s = RunSlam(p.Get("RECORDING"), config, p.Get("out"), &r, run); !s) return Fail(s);
  std::printf("%zu scans, median %.1f ms per scan, %.1fx real time; outputs in %s\n", r.scans.size(),
              r.median_scan_ms, r.wall_time_s > 0 ? r.data_duration_s / r.wall_time_s : 0.0, p.Get("out").c_str());
  PrintScanHealth(r.scans);
  RunEvaluationOptions score;  // the ATE when the recording has truth (bench may read truth/); map metrics on --score
  score.map_metrics = p.Flag("score");
  score.dynamic.voxel_m = config.output_map_voxel_m;  // voxels seen counted in the dense map's own voxel
  if (score.map_metrics) std::fprintf(stderr, "scoring the map against the scene (--score)\n");
  RunEvaluation ev;
  if (Status s = WriteSlamRunReport(p.Get("RECORDING"), p.Get("out"), r, score, &ev); !s) return Fail(s);
  if (config.loop_closure.enabled) PrintLoopClosure(r.loops);
  if (r.loop_snapshots > 0)
    std::printf("%zu loop snapshots (map and trajectory after each correction) in %s/loop_snapshots/\n",
                r.loop_snapshots, p.Get("out").c_str());
  if (ev.has_truth)
    std::printf("ATE vs truth (SE(3)): RMSE %.4f m over %zu poses\n", ev.ape.stats.rmse, ev.ape.num_associated);
  if (ev.has_map_metrics)
    std::printf("map: map-to-truth median %.4f m, coverage %.1f %%, element size RMSE %.3f m (%.0f s)\n",
                ev.map.map_to_truth.median_m, 100 * ev.map.coverage.total.coverage, ev.map.element_summary.rmse_m,
                ev.map_metrics_wall_s);
  else if (score.map_metrics)
    std::printf("no map metrics: %s\n", ev.map_note.c_str());
  if (ev.has_dynamic && ev.dynamic.returns_seen > 0)
    std::printf("%s\n%s", DynamicShareLine(ev.dynamic).c_str(), DynamicObjectLines(ev.dynamic).c_str());
  std::printf("report: %s/report.html\n", p.Get("out").c_str());
  if (r.stopped) {
    std::fprintf(stderr, "slam: stopped by %s after %.1f s of LiDAR data: the outputs are partial (metrics.json: "
                 "\"complete\": false)\n", stop_on_signals.name(), r.data_fed_s);
    return 128 + stop_on_signals.signal();
  }
  return 0;
}

}  // namespace rotolidar::bench
