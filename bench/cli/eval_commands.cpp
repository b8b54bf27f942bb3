// eval and decode: the measurement commands.
#include <cstdio>
#include <iostream>
#include <sstream>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/decode/decode.hpp"
#include "bench/run/eval_run.hpp"

namespace rotolidar::bench {
namespace {

/// A default for the help table, printed as C++ prints it (0.4, 130).
std::string FormatNumber(double value) {
  std::ostringstream os;
  os << value;
  return os.str();
}

Status ParseEvalOptions(const OptionParser& p, EvalOptions* o) {
  o->ref_path = p.Get("REF");
  o->est_path = p.Get("EST");
  if (!ParseTrajectoryFormat(p.Get("format"), &o->format)) return Status::Error("eval: --format: tum, kitti or euroc");
  if (!ParseAlignment(p.Get("align"), &o->align)) return Status::Error("eval: --align: none, se3, sim3 or posyaw");
  if (!ParseEvalMetric(p.Get("metric"), &o->metric)) return Status::Error("eval: --metric: ape, rpe or kitti");
  if (!ParsePoseRelation(p.Get("relation"), &o->pose_relation))
    return Status::Error("eval: --relation: trans_part, angle_deg, angle_rad, full, rot_part");
  if (!ParseDeltaUnit(p.Get("delta-unit"), &o->delta_unit)) return Status::Error("eval: --delta-unit: frames or m");
  if (Status s = p.GetDouble("delta", &o->delta); !s) return s;
  if (Status s = p.GetDouble("max-diff", &o->max_diff_s); !s) return s;
  o->all_pairs = p.Flag("all-pairs");
  o->json_path = p.Get("json");
  std::string why;
  if (!o->Validate(&why)) return Status::Error("eval: " + why);
  return Status::Ok();
}

}  // namespace

int CmdEval(int argc, char** argv) {
  OptionParser p("eval", "Compare an estimated trajectory with a reference: APE or RPE statistics, evo's "
                         "definitions (max, mean, median, min, rmse, sse, std), or the KITTI odometry "
                         "devkit's segment errors (--metric kitti: mean = t_rel [%] or r_rel [deg/100m]).");
  p.AddPositional("REF", "reference trajectory file");
  p.AddPositional("EST", "estimated trajectory file");
  p.Add("format", "tum", "-", "tum | kitti | euroc");
  p.Add("align", "none", "-", "none | se3 | sim3 | posyaw (Umeyama)");
  p.Add("metric", "ape", "-", "ape | rpe | kitti (KITTI devkit: t_rel over 100-800 m segments)");
  p.Add("relation", "trans_part", "-", "trans_part | angle_deg | angle_rad | full | rot_part (kitti: trans_part "
                                                "or angle_deg)");
  p.Add("delta", "1", "frames|m", "RPE pair distance");
  p.Add("delta-unit", "frames", "-", "frames | m");
  p.AddFlag("all-pairs", "RPE: use all pairs, not consecutive non-overlapping ones");
  p.Add("max-diff", "0.01", "s", "timestamp association tolerance (tum, euroc)");
  p.Add("json", "", "-", "write the statistics as JSON to this file");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  EvalOptions options;
  if (Status s = ParseEvalOptions(p, &options); !s) return Usage(s.message);
  EvalResult result;
  if (Status s = RunEval(options, &result); !s) {
    std::cerr << "error: " << s.message << "\n";
    return 1;
  }
  PrintEvalStats(result, std::cout);
  return 0;
}

int CmdDecode(int argc, char** argv) {
  OptionParser p("decode", "Decode VLP-16 data packets into points: <out>.csv (x,y,z,intensity,ring,azimuth,return,"
                           "time_s, one row per point) and <out>.ply. Fails when no point comes out, naming "
                           "what the input held instead.");
  p.AddPositional("INPUT", "a .pcap/.pcapng capture, or concatenated 1206-byte payloads with --raw");
  p.Add("out", "decoded", "-", "output prefix");
  p.AddFlag("raw", "input is headerless concatenated 1206-byte payloads (no pcap)");
  p.Add("return", "all", "-", "all | strongest | last");
  const Vlp16DecoderConfig defaults;
  p.Add("min-range", FormatNumber(defaults.min_range_m), "m", "drop closer returns");
  p.Add("max-range", FormatNumber(defaults.max_range_m), "m", "drop farther returns");
  p.Add("clock-offset", "0", "s", "rig time = VLP-16 time past the hour + this");
  p.Add("cut-azimuth", "0", "deg", "revolutions start where the azimuth crosses this");
  p.Add("revolution", "-1", "-", "write only this revolution (0 = first, usually partial); -1 = all points");
  p.AddFlag("strict", "stop at the first malformed packet instead of counting it");
  p.AddFlag("keep-dual-duplicates", "dual return: keep both copies of an echo that is both the strongest and the "
                                    "last (default: one point, return 2)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  DecodeOptions o;
  o.input_path = p.Get("INPUT");
  o.output_prefix = p.Get("out");
  o.raw = p.Flag("raw");
  o.strict = p.Flag("strict");
  o.decoder.keep_duplicate_dual_returns = p.Flag("keep-dual-duplicates");
  if (!ParseReturnFilter(p.Get("return"), &o.decoder.return_filter)) return Usage("decode: --return: all, strongest or last");
  long revolution = -1;
  for (const Status& s : {p.GetDouble("min-range", &o.decoder.min_range_m),
                          p.GetDouble("max-range", &o.decoder.max_range_m),
                          p.GetDouble("clock-offset", &o.decoder.lidar_clock_offset_s),
                          p.GetDouble("cut-azimuth", &o.cut_azimuth_deg), p.GetInt("revolution", &revolution)})
    if (!s) return Usage(s.message);
  o.revolution = int(revolution);
  DecodeSummary summary;
  if (Status s = RunDecode(o, &summary); !s) {
    std::cerr << "error: " << s.message << "\n";
    return 1;
  }
  PrintDecodeSummary(summary, std::cout);
  return 0;
}

}  // namespace rotolidar::bench
