// truth/clocks.yaml with the project's one YAML idiom (core/io/yaml_fields.hpp).
#include "sim/truth/clock_truth.hpp"

#include <fstream>

#include "core/io/yaml_fields.hpp"

namespace rotolidar::sim {

template <class V>
void Visit(V& v, SensorClock& c) {
  v("offset_s", &c.offset_s), v("drift_ppm", &c.drift_ppm);
}

template <class V>
void Visit(V& v, CaptureJitterConfig& c) {
  v("latency_s", &c.latency_s), v("jitter_scale_s", &c.jitter_scale_s);
}

template <class V>
void Visit(V& v, ClockTruth& c) {
  v("lidar", &c.lidar), v("lidar_pps_synced", &c.lidar_pps_synced), v("imu", &c.imu), v("encoder", &c.encoder);
  v("camera", &c.camera), v("lidar_capture", &c.lidar_capture);
}

namespace {
std::string ClocksPath(const std::string& recording_dir) { return recording_dir + "/truth/clocks.yaml"; }
}  // namespace

Status WriteClockTruth(const std::string& recording_dir, const ClockTruth& clocks) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // reads back to the identical double
  yaml::Emit(out, clocks);
  const std::string path = ClocksPath(recording_dir);
  std::ofstream file(path);
  file << "# True sensor clocks of this run: stamp = t + offset_s + drift_ppm * 1e-6 * t, t on the rig clock [s]\n"
       << out.c_str() << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

Status ReadClockTruth(const std::string& recording_dir, ClockTruth* clocks) {
  const std::string path = ClocksPath(recording_dir);
  ClockTruth c;
  try {
    yaml::Parse(yaml::Section(path, "", "clocks"), yaml::LoadFile(path), &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  *clocks = c;
  return Status::Ok();
}

}  // namespace rotolidar::sim
