// `rotolidar bench rig|allan|lidar|decode|slam|camera`: each benchmark's options, help text, argument checks and
// output. The measurements themselves are bench/perf/'s Run*Bench functions (contracts in their headers).
#include "bench/cli/perf_commands.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "bench/cli/options.hpp"
#include "bench/perf/camera_perf.hpp"
#include "bench/perf/lidar_perf.hpp"
#include "bench/perf/rig_perf.hpp"
#include "bench/perf/slam_perf.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::bench {
namespace {

/// "strongest" | "last" | "dual".
bool ParseReturnMode(const std::string& text, Vlp16ReturnMode* mode) {
  if (text == "strongest") *mode = Vlp16ReturnMode::kStrongest;
  else if (text == "last") *mode = Vlp16ReturnMode::kLast;
  else if (text == "dual") *mode = Vlp16ReturnMode::kDual;
  else return false;
  return true;
}

/// "W1xH1,W2xH2,...": false on anything else or an empty list.
bool ParseSizes(const std::string& text, std::vector<std::pair<int, int>>* sizes) {
  sizes->clear();
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    int w = 0, h = 0;
    char x = 0;
    std::stringstream one(item);
    if (!(one >> w >> x >> h) || x != 'x') return false;
    sizes->emplace_back(w, h);
  }
  return !sizes->empty();
}

}  // namespace

int BenchRig(int argc, char** argv) {
  sim::SimConfig config = sim::DefaultSimConfig();
  OptionParser p("bench rig", "Rig twin speed without the LiDAR: MuJoCo physics + stepper drive (PID, encoder) + "
                              "IMU model, one thread. Prints simulated seconds per CPU second (target >= 100x).");
  p.Add("config", "", "-", "sim config YAML (carrier, motor, rig_model, imu); default: built-in");
  p.Add("duration", "60", "s", "simulated time");
  p.Add("repeat", "3", "-", "repetitions (the median is reported)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  long repeat = 3;
  if (Status s = p.GetDouble("duration", &config.duration_s); !s) return std::cerr << "error: " << s.message << "\n", 2;
  if (Status s = p.GetInt("repeat", &repeat); !s || repeat < 1) return std::cerr << "error: --repeat >= 1\n", 2;
  if (!p.Get("config").empty()) {
    const double duration = config.duration_s;
    if (Status s = sim::LoadSimConfig(p.Get("config"), &config); !s) return std::cerr << "error: " << s.message << "\n", 1;
    config.duration_s = duration;
  }
  std::vector<double> ratios;
  for (long i = 0; i < repeat; ++i) {
    RigBenchResult r;
    if (Status s = RunRigBench(config, &r); !s) return std::cerr << "error: " << s.message << "\n", 1;
    std::printf("run %ld: %.1f s simulated, %ld steps, %ld IMU, %ld encoder samples in %.2f s CPU (%.2f s wall): "
                "%.1fx real time\n", i + 1, r.sim_s, r.physics_steps, r.imu_samples, r.encoder_samples, r.cpu_s,
                r.wall_s, r.RealTimeRatio());
    ratios.push_back(r.RealTimeRatio());
  }
  std::sort(ratios.begin(), ratios.end());
  std::printf("rig physics + IMU + encoder: median %.1fx real time on 1 core\n", ratios[ratios.size() / 2]);
  return 0;
}

int BenchAllan(int argc, char** argv) {
  sim::SimConfig config = sim::DefaultSimConfig();
  OptionParser p("bench allan", "Static rig through physics + IMU model; recovers the configured noise densities "
                                "and random walks from the Allan deviation (bar: within 10 %).");
  p.Add("hours", "24", "h", "static record length (BMI055 gyro K: 24 h gives 10 % at > 95 % confidence, docs)");
  p.Add("seed", "1", "-", "run seed");
  p.Add("table", "", "-", "write the tau/adev table (CSV) here");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  double hours = 24;
  long seed = 1;
  if (Status s = p.GetDouble("hours", &hours); !s) return std::cerr << "error: " << s.message << "\n", 2;
  if (Status s = p.GetInt("seed", &seed); !s) return std::cerr << "error: " << s.message << "\n", 2;
  config.seed = uint64_t(seed);
  AllanBenchResult r;
  if (Status s = RunAllanBench(config, hours, &r); !s) return std::cerr << "error: " << s.message << "\n", 1;
  if (!p.Get("table").empty()) {
    std::ofstream table(p.Get("table"));
    WriteAllanTable(table, r.report);
  }
  const ImuNoise& n = r.configured;
  std::printf("%.1f h static (%ld samples) in %.1f s CPU (%.0fx real time)\n", hours, r.run.imu_samples, r.run.cpu_s,
              r.run.RealTimeRatio());
  for (int a = 0; a < 3; ++a)
    std::printf("axis %c: gyro N %.4g (cfg %.4g) K %.4g (cfg %.4g) | accel N %.4g (cfg %.4g) K %.4g (cfg %.4g)\n",
                "xyz"[a], r.report.gyro[a].fit.white_density, n.gyro_noise_density, r.report.gyro[a].fit.random_walk,
                n.gyro_random_walk, r.report.accel[a].fit.white_density, n.accel_noise_density,
                r.report.accel[a].fit.random_walk, n.accel_random_walk);
  const auto row = [](const char* name, const AllanSensorFit& f, double n_cfg, double k_cfg) {
    std::printf("%-5s (3-axis mean): N %.4g (cfg %.4g, %+.1f %%)  K %.4g (cfg %.4g, %+.1f %%)  | worst axis: N %.1f %%, "
                "K %.1f %%\n", name, f.white_density, n_cfg, 100 * (f.white_density / n_cfg - 1), f.random_walk, k_cfg,
                100 * (f.random_walk / k_cfg - 1), 100 * f.worst_axis_n_error, 100 * f.worst_axis_k_error);
  };
  row("gyro", r.gyro, n.gyro_noise_density, n.gyro_random_walk);
  row("accel", r.accel, n.accel_noise_density, n.accel_random_walk);
  const bool pass = r.Pass(0.1);
  std::printf("%s\n", pass ? "PASS: each sensor's N and K within 10 %" : "FAIL: some term outside 10 %");
  return pass ? 0 : 1;
}

int BenchLidar(int argc, char** argv) {
  OptionParser p("bench lidar", "Speed of the simulated VLP-16 (ray casting against a scene, default rig motion) "
                                "as a ratio to real time (289,344 firings/s), one thread, medians of repetitions.");
  p.Add("scene", "box_room", "-", "scene name (scenes/NAME.yaml) or path");
  p.Add("seconds", "1", "s", "simulated time per repetition");
  p.Add("reps", "5", "-", "repetitions (median reported)");
  p.Add("rpm", "600", "rpm", "head spin rate (300..1200)");
  p.Add("return", "strongest", "-", "strongest | last | dual");
  p.Add("beam-rings", "0", "-", "beam divergence sub-ray rings: 0 = central ray, n = 1 + 3n(n+1) rays");
  p.AddFlag("truth", "also collect per-firing truth (as the tests do)");
  p.AddFlag("pose-per-firing", "call the rig pose for every firing instead of once per sequence");
  p.Add("seed", "1", "-", "run seed");
  p.Add("realism", "", "-", "ideal | typical | harsh: the preset's range physics (its beam rings replace --beam-rings)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  LidarBenchOptions o;
  o.realism = p.Get("realism");
  o.scene = p.Get("scene");
  long reps = 0, rings = 0, seed = 0;
  for (const Status& s : {p.GetDouble("seconds", &o.seconds), p.GetInt("reps", &reps), p.GetDouble("rpm", &o.rpm),
                          p.GetInt("beam-rings", &rings), p.GetInt("seed", &seed)}) {
    if (!s) return std::cerr << "error: " << s.message << "\n", 2;
  }
  if (!ParseReturnMode(p.Get("return"), &o.return_mode)) {
    return std::cerr << "error: bench lidar: --return: strongest, last or dual\n", 2;
  }
  o.repetitions = static_cast<int>(reps);
  o.beam_rings = static_cast<int>(rings);
  o.seed = static_cast<uint64_t>(seed);
  o.truth = p.Flag("truth");
  o.pose_per_firing = p.Flag("pose-per-firing");
  if (std::string why; !o.Validate(&why)) return std::cerr << "error: " << why << "\n", 2;
  LidarBenchResult result;
  if (Status s = RunLidarBench(o, &result); !s) return std::cerr << "error: " << s.message << "\n", 1;
  PrintLidarBench(o, result, std::cout);
  return 0;
}

int BenchDecode(int argc, char** argv) {
  OptionParser p("bench decode", "Speed of the VLP-16 decoder (packets -> timed points) as a ratio to real time "
                                 "(the time the packets span), one thread, medians of repetitions.");
  p.Add("input", "", "-", "pcap file (or raw payloads with --raw); empty = simulate the default rig");
  p.AddFlag("raw", "input is concatenated 1206-byte payloads");
  p.Add("seconds", "2", "s", "length of the simulated stream");
  p.Add("mode", "strongest", "-", "return mode of the simulated stream: strongest | last | dual");
  p.Add("reps", "5", "-", "repetitions (median reported)");
  p.AddFlag("split", "also cut revolutions in the timed loop");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  DecodeBenchOptions o;
  o.input = p.Get("input");
  o.raw = p.Flag("raw");
  o.split = p.Flag("split");
  long reps = 0;
  for (const Status& s : {p.GetDouble("seconds", &o.seconds), p.GetInt("reps", &reps)}) {
    if (!s) return std::cerr << "error: " << s.message << "\n", 2;
  }
  if (!ParseReturnMode(p.Get("mode"), &o.mode)) {
    return std::cerr << "error: bench decode: --mode: strongest, last or dual\n", 2;
  }
  o.repetitions = static_cast<int>(reps);
  if (std::string why; !o.Validate(&why)) return std::cerr << "error: " << why << "\n", 2;
  DecodeBenchResult result;
  if (Status s = RunDecodeBench(o, &result); !s) return std::cerr << "error: " << s.message << "\n", 1;
  PrintDecodeBench(o, result, std::cout);
  return 0;
}

int BenchSlam(int argc, char** argv) {
  OptionParser p("bench slam", "Simulate a recording, run the SLAM core on it and report per-scan time per stage, "
                               "the real-time ratio (data span / estimator CPU time), ATE and the per-point deskew "
                               "error against truth (target: median <= 10 ms per scan on 1 core).");
  p.Add("scene", "lab", "-", "scene name (scenes/NAME.yaml) or path");
  p.Add("duration", "20", "s", "simulated time");
  p.Add("seed", "1", "-", "run seed of the simulation");
  p.Add("carrier", "handheld", "-", "handheld (the scene's default walk) | scripted_loop");
  p.Add("reps", "2", "-", "estimator runs over the recording (the first scores deskew and ATE; the others are timed)");
  p.Add("threads", "1", "-", "estimator threads (features, Ceres)");
  p.Add("camera", "off", "-", "on: render the camera and fuse it (LiDAR-visual-inertial)");
  p.Add("recording", "runs/bench_slam/recording", "-", "folder the simulated recording is written to");
  p.Add("json", "", "-", "also write the results to this JSON file");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  SlamBenchOptions o;
  o.scene = p.Get("scene");
  o.carrier = p.Get("carrier");
  o.recording_dir = p.Get("recording");
  if (p.Get("camera") != "on" && p.Get("camera") != "off")
    return std::cerr << "error: --camera must be on or off (got '" << p.Get("camera") << "')\n", 2;
  o.camera = p.Get("camera") == "on";
  long seed = 0, reps = 0, threads = 0;
  for (const Status& s : {p.GetDouble("duration", &o.duration_s), p.GetInt("seed", &seed), p.GetInt("reps", &reps),
                          p.GetInt("threads", &threads)}) {
    if (!s) return std::cerr << "error: " << s.message << "\n", 2;
  }
  o.seed = static_cast<uint64_t>(seed);
  o.repetitions = static_cast<int>(reps);
  o.threads = static_cast<int>(threads);
  if (std::string why; !o.Validate(&why)) return std::cerr << "error: " << why << "\n", 2;
  SlamBenchResult result;
  if (Status s = RunSlamBench(o, &result); !s) return std::cerr << "error: " << s.message << "\n", 1;
  PrintSlamBench(o, result, std::cout);
  if (const std::string json = p.Get("json"); !json.empty()) {
    if (Status s = WriteSlamBenchJson(json, o, result); !s) return std::cerr << "error: " << s.message << "\n", 1;
    std::cout << "wrote " << json << "\n";
  }
  return 0;
}

int BenchCamera(int argc, char** argv) {
  OptionParser p("bench camera", "Frames per second of the camera twin for each renderer and image size, along the "
                                 "scene's handheld path (medians of frames).");
  p.Add("scene", "lab", "-", "scene name (scenes/NAME.yaml) or path");
  p.Add("renderer", "both", "-", "embree | osmesa | both");
  p.Add("frames", "60", "-", "timed frames per renderer and size");
  p.Add("sizes", "640x480,1280x720", "px", "comma-separated WIDTHxHEIGHT list (fx scaled to keep the field of view)");
  p.Add("threads", "2", "-", "worker threads (render, blur, sensor)");
  p.Add("blur", "velocity", "-", "motion blur: none | velocity | subframes");
  p.Add("seed", "1", "-", "run seed (sensor noise)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  CameraBenchOptions o;
  o.scene = p.Get("scene");
  long frames = 0, threads = 0, seed = 0;
  for (const Status& s : {p.GetInt("frames", &frames), p.GetInt("threads", &threads), p.GetInt("seed", &seed)})
    if (!s) return std::cerr << "error: " << s.message << "\n", 2;
  o.frames = static_cast<int>(frames);
  o.threads = static_cast<int>(threads);
  o.seed = static_cast<uint64_t>(seed);
  o.motion_blur = p.Get("blur");
  const std::string renderer = p.Get("renderer");
  o.renderers = renderer == "both" ? std::vector<std::string>{"embree", "osmesa"} : std::vector<std::string>{renderer};
  if (!ParseSizes(p.Get("sizes"), &o.sizes)) return std::cerr << "error: bench camera: --sizes: e.g. 640x480,1280x720\n", 2;
  if (std::string why; !o.Validate(&why)) return std::cerr << "error: " << why << "\n", 2;
  std::vector<CameraBenchRow> rows;
  if (Status s = RunCameraBench(o, &rows); !s) return std::cerr << "error: " << s.message << "\n", 1;
  PrintCameraBench(o, rows, std::cout);
  return 0;
}

}  // namespace rotolidar::bench
