// `rotolidar bench loops`: loop detection precision/recall against the twin's truth (bench/loops/loop_pr.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>

#include <nlohmann/json.hpp>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/cli/perf_commands.hpp"
#include "bench/eval/trajectory_lookup.hpp"
#include "bench/loops/loop_report.hpp"
#include "bench/run/progress.hpp"
#include "bench/run/slam_run.hpp"
#include "core/io/trajectory_io.hpp"

namespace rotolidar::bench {
namespace {

Status WriteSummaryJson(const std::string& path, const LoopPrResult& r, const graph::LoopClosureState& state,
                        const std::vector<LoopTruthCheck>& checks, const LoopPrConfig& c) {
  nlohmann::json j;
  j["queries"] = r.queries.size();
  j["positives"] = r.positives;
  j["operating_point"] = {{"descriptor_distance", c.loop.max_descriptor_distance},
                          {"fitness_rmse_m", c.loop.verification.max_fitness_rmse_m},
                          {"precision", r.operating.precision},
                          {"recall", r.operating.recall},
                          {"true_detections", r.operating.tp},
                          {"false_detections", r.operating.fp}};
  int false_loops = 0, false_kept = 0, rejected = 0;
  double max_error_m = 0.0;
  for (size_t i = 0; i < checks.size(); ++i) {
    false_loops += !checks[i].correct, rejected += state.loops[i].rejected;
    false_kept += !checks[i].correct && !state.loops[i].rejected;
    if (!state.loops[i].rejected) max_error_m = std::max(max_error_m, checks[i].error_m);
  }
  j["run"] = {{"loops_accepted", state.loops.size()},  {"false_loops", false_loops},
              {"false_loops_kept", false_kept},         {"rejected_by_graph", rejected},
              {"max_kept_loop_error_m", max_error_m}};
  j["truth"] = {{"revisit_max_distance_m", c.revisit_max_distance_m},
                {"revisit_min_overlap", c.revisit_min_overlap},
                {"overlap_radius_m", c.overlap_radius_m},
                {"max_loop_error_m", c.max_loop_error_m},
                {"max_loop_error_rad", c.max_loop_error_rad}};
  j["recall_at_precision_1"] = {{"stage1", RecallAtPrecision1(r.stage1)},
                                 {"stage2", RecallAtPrecision1(r.stage2)},
                                 {"both", RecallAtPrecision1(r.both)}};
  if (r.visual_absent.empty()) {
    j["recall_at_precision_1"]["visual_stage1"] = RecallAtPrecision1(r.visual);
    j["visual_stage1"] = {{"keyframes_with_bow", r.visual_keyframes},
                          {"min_normalised_score", r.visual_operating.threshold},
                          {"min_raw_score", c.loop.bow.min_raw_score},
                          {"precision", r.visual_operating.precision},
                          {"recall", r.visual_operating.recall},
                          {"true_detections", r.visual_operating.tp},
                          {"false_detections", r.visual_operating.fp}};
  } else {
    j["visual_stage1"] = {{"keyframes_with_bow", 0}, {"absent", r.visual_absent}};
  }
  j["verify_time_s"] = r.verify_time_s;
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  return out ? Status::Ok() : Status::Error(path + ": write failed");
}

}  // namespace

int BenchLoops(int argc, char** argv) {
  OptionParser p("bench loops", "Run the SLAM core with loop closure on a recording with truth, then rate loop "
                                "detection against the truth revisits: precision/recall curves of stage 1 alone, "
                                "stage 2 alone and both (and the visual stage 1 alone, ORB bag of words, when the "
                                "config has a vocabulary and the recording a camera), the operating point, and the run's own loops (false ones "
                                "counted). Writes OUT/loops.html, loop_pr.csv, loop_queries.csv, loop_pr.json and "
                                "the slam run in OUT/slam.");
  p.AddPositional("RECORDING", "recording folder with truth/ (rotolidar sim)");
  p.Add("out", "runs/bench_loops", "-", "output folder");
  p.Add("config", "", "-", "estimator config YAML (loop closure is switched on; its gates are the operating point)");
  p.Add("revisit-distance", "10", "m", "truth: a true revisit's keyframes are at most this far apart");
  p.Add("revisit-overlap", "0.3", "-", "truth: and this share of the query's points is seen again (truth poses)");
  p.Add("descriptor-window", "", "s", "loop_closure.descriptor_window_s for the run and the curves (none: the "
                                     "--config value, default 2.5): describe each keyframe with the keyframes "
                                     "of the last this many seconds (0: its own scan)");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  EstimatorConfig config;
  if (Status s = LoadSlamConfig(p.Get("config"), &config); !s) return Fail(s);
  config.loop_closure.enabled = true;
  if (!p.Get("descriptor-window").empty())  // else the --config value (default 0)
    if (Status s = p.GetDouble("descriptor-window", &config.loop_closure.descriptor_window_s); !s) return Fail(s, 2);
  LoopPrConfig pr;
  pr.loop = config.loop_closure;
  if (Status s = p.GetDouble("revisit-distance", &pr.revisit_max_distance_m); !s) return Fail(s, 2);
  if (Status s = p.GetDouble("revisit-overlap", &pr.revisit_min_overlap); !s) return Fail(s, 2);
  if (std::string why; !pr.Validate(&why)) return Fail(Status::Error(why), 2);

  const std::string out = p.Get("out");
  SlamRunResult slam;
  SlamRunOptions run;
  run.progress = MakeProgressPrinter("slam");
  run.keep_keyframes = true;
  if (Status s = RunSlam(p.Get("RECORDING"), config, out + "/slam", &slam, run); !s) return Fail(s);
  PrintLoopClosure(slam.loops);
  std::vector<Pose3> T_truth_base;
  if (Status s = TruthAtKeyframes(p.Get("RECORDING"), slam.loop_keyframes, &T_truth_base); !s) return Fail(s);
  std::fprintf(stderr, "rating %zu keyframes against truth (two GICP runs per query)\n", slam.loop_keyframes.size());
  LoopPrResult r;
  if (Status s = EvaluateLoopPr(slam.loop_keyframes, T_truth_base, pr, &r, MakeProgressPrinter("loops")); !s)
    return Fail(s);
  const RevisitTruth truth(slam.loop_keyframes, T_truth_base, pr);
  std::vector<LoopTruthCheck> checks;
  int false_loops = 0, false_kept = 0;
  for (const graph::LoopRecord& l : slam.loops.loops) {
    checks.push_back(CheckLoop(truth, l, pr));
    false_loops += !checks.back().correct;
    false_kept += !checks.back().correct && !l.rejected;
  }
  if (Status s = WriteLoopPrOutputs(out, p.Get("RECORDING"), r, slam.loops, checks); !s) return Fail(s);
  if (Status s = WriteSummaryJson(out + "/loop_pr.json", r, slam.loops, checks, pr); !s) return Fail(s);
  std::printf("queries %zu, positives %d; operating point (descriptor <= %.2f, fitness <= %.2f m): precision %.3f, "
              "recall %.3f (%d true, %d false)\n",
              r.queries.size(), r.positives, pr.loop.max_descriptor_distance, pr.loop.verification.max_fitness_rmse_m,
              r.operating.precision, r.operating.recall, r.operating.tp, r.operating.fp);
  std::printf("recall at precision 1: stage 1 alone (Scan Context) %.3f, stage 2 alone %.3f, both %.3f\n",
              RecallAtPrecision1(r.stage1), RecallAtPrecision1(r.stage2), RecallAtPrecision1(r.both));
  if (r.visual_absent.empty())
    std::printf("visual stage 1 alone (%d keyframes with a bag-of-words vector): recall at precision 1 %.3f; at eta "
                ">= %.2f: precision %.3f, recall %.3f (%d true, %d false)\n", r.visual_keyframes,
                RecallAtPrecision1(r.visual), r.visual_operating.threshold, r.visual_operating.precision,
                r.visual_operating.recall, r.visual_operating.tp, r.visual_operating.fp);
  else
    std::printf("visual stage 1 alone: not rated, %s\n", r.visual_absent.c_str());
  std::printf("run: %zu loops accepted by stage 2, %d false (relative pose off the truth by > %.2f m or %.1f deg), "
              "%d of them kept by the pose graph; report: %s/loops.html\n", slam.loops.loops.size(), false_loops,
              pr.max_loop_error_m, pr.max_loop_error_rad * 180.0 / M_PI, false_kept, out.c_str());
  return 0;
}

}  // namespace rotolidar::bench
