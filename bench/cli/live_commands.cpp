// `rotolidar live`: SLAM from the rig's sensors over UDP (bench/live/live_session.hpp; protocol in docs/live.md).
// SIGINT / SIGTERM stop it cleanly: the readers stop, what they hold is fed, the outputs are written.
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/cli/signals.hpp"
#include "bench/live/live_session.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"

namespace rotolidar::bench {
namespace {

Status Port(const OptionParser& p, const char* name, uint16_t* port) {
  long v = 0;
  if (Status s = p.GetInt(name, &v); !s) return s;
  if (v < 0 || v > 65535) return Status::Error(std::string("--") + name + ": must be 0..65535 (0 = any free port)");
  *port = static_cast<uint16_t>(v);
  return Status::Ok();
}

Status ReadLiveOptions(const OptionParser& p, LiveConfig* c) {
  c->bind_address = p.Get("bind");
  long pending = 0;
  for (const Status& s : {Port(p, "port", &c->data_port), Port(p, "position-port", &c->position_port),
                          Port(p, "rig-port", &c->rig_port), p.GetDouble("hold", &c->merge.hold_s),
                          p.GetInt("max-pending-scans", &pending), p.GetDouble("snapshot-period", &c->snapshot_period_s),
                          p.GetDouble("status-period", &c->status_period_s), p.GetDouble("idle-stop", &c->idle_stop_s),
                          p.GetDouble("duration", &c->duration_s)})
    if (!s) return s;
  if (pending < 1) return Status::Error("--max-pending-scans: must be >= 1");
  c->max_pending_scans = static_cast<std::size_t>(pending);
  std::string why;
  if (!c->Validate(&why)) return Status::Error(why);
  return Status::Ok();
}

}  // namespace

int CmdLive(int argc, char** argv) {
  OptionParser p("live", "SLAM from the rig's sensors as they send: VLP-16 data and position packets and the rig's "
                         "IMU/encoder samples (docs/live.md) over UDP. Writes everything received into "
                         "OUT/recording/ (replayable with `rotolidar slam`), snapshots of trajectory.tum and "
                         "map.ply, and at the end the outputs of `rotolidar slam` plus live.json. Ctrl-C stops.");
  p.Add("calib", "", "-", "the rig's calib.yaml (required)");
  p.Add("config", "", "-", "estimator config YAML (keys of slam_config.yaml)");
  p.Add("out", "runs/live", "-", "output folder (must not hold an earlier session's recording)");
  p.Add("bind", "0.0.0.0", "-", "IPv4 address of the interface to listen on (0.0.0.0: all)");
  p.Add("port", "2368", "-", "UDP port of VLP-16 data packets (0: any free port, printed)");
  p.Add("position-port", "8308", "-", "UDP port of VLP-16 position packets");
  p.Add("rig-port", "2370", "-", "UDP port of rig samples (IMU, encoder)");
  p.Add("hold", "0.25", "s", "longest a packet waits for the rig samples of its time");
  p.Add("max-pending-scans", "3", "-", "behind by more revolutions than this: drop the oldest whole scans, keep the newest");
  p.Add("snapshot-period", "10", "s", "wall time between trajectory/map snapshots (0: none)");
  p.Add("status-period", "1", "s", "wall time between status lines");
  p.Add("idle-stop", "0", "s", "stop when no data came for this long after the first (0: never)");
  p.Add("duration", "0", "s", "stop after this long (0: only on Ctrl-C / SIGTERM)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  if (p.Get("calib").empty()) return Fail(Status::Error("--calib: required (the rig's calib.yaml)"));
  RigCalib calib;
  if (Status s = LoadCalibYaml(p.Get("calib"), &calib); !s) return Fail(s);
  EstimatorConfig estimator;
  if (Status s = LoadSlamConfig(p.Get("config"), &estimator); !s) return Fail(s);
  LiveConfig config;
  if (Status s = ReadLiveOptions(p, &config); !s) return Fail(s);
  const std::string out = p.Get("out");
  if (std::filesystem::exists(out + "/recording"))
    return Fail(Status::Error(out + "/recording: exists (an earlier session); choose another --out"));
  LiveSession session(calib, estimator, config, out);
  if (Status s = session.Start(); !s) return Fail(s);
  std::fprintf(stderr, "live: listening on %s: data %u, position %u, rig samples %u; recording into %s/recording\n",
               config.bind_address.c_str(), session.data_port(), session.position_port(), session.rig_port(),
               out.c_str());
  StopOnSignals stop;  // Ctrl-C / SIGTERM: stop the readers, feed what they hold, write the outputs
  const Status run =
      session.Run(stop.flag(), [](const LiveStatus& s) { std::fprintf(stderr, "%s\r", s.Line().c_str()); });
  std::fprintf(stderr, "\n");
  if (stop.signal() != 0) std::fprintf(stderr, "live: stopped by %s; outputs written\n", stop.name());
  if (!run) return Fail(run);
  const LiveStatus s = session.status();
  std::printf("%zu scans processed, %zu dropped; lost %zu data packets (timestamp gaps), %zu rig datagrams, %zu in "
              "the kernel; outputs in %s\n",
              s.scans, s.scans_dropped, s.packets_lost, s.rig_lost, s.kernel_dropped, out.c_str());
  return 0;
}

}  // namespace rotolidar::bench
