#pragma once
// Pictures and files of loop closure: the loop edges on a top view (the run report's "loops" section and
// `rotolidar bench loops`), the precision/recall curves, and bench loops' tables and page.
#include <string>
#include <vector>

#include "bench/loops/loop_pr.hpp"
#include "core/graph/loop_closer.hpp"

namespace rotolidar::bench {

/// Truth verdict of each accepted loop (state.loops order): 1 true revisit, 0 false, -1 unknown (no truth).
using LoopVerdicts = std::vector<int>;

/// Top view [SLAM world, m] of the keyframes' odometry and corrected positions, each loop a segment between its two
/// keyframes' corrected positions: green true (or unknown), red false, grey dashed when the graph rejected it.
std::string LoopTopViewSvg(const graph::LoopClosureState& state, const LoopVerdicts& verdicts);

/// Precision against recall of the three detectors and, when rated, the visual stage 1 alone; the operating
/// point (and the visual stage 1's at the seed's eta) marked.
std::string LoopPrSvg(const LoopPrResult& result);

/// Writes into out_dir: loop_pr.csv (curve, threshold, precision, recall, tp, fp; curves stage1, stage2, both,
/// operating and, when rated, visual (descending eta) and visual_operating), loop_queries.csv (one row per
/// query: each detector's proposal, score and truth), loops_truth.csv (each accepted loop against the truth; `checks`
/// in state.loops order) and loops.html (the curves, the top view, the tables).
Status WriteLoopPrOutputs(const std::string& out_dir, const std::string& title, const LoopPrResult& result,
                          const graph::LoopClosureState& state, const std::vector<LoopTruthCheck>& checks);

}  // namespace rotolidar::bench
