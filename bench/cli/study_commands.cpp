// `rotolidar study STUDY.yaml`: trade studies (bench/study/, docs/studies.md).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>

#include "bench/cli/commands.hpp"
#include "bench/cli/options.hpp"
#include "bench/cli/signals.hpp"
#include "bench/study/study_config.hpp"
#include "bench/study/study_report.hpp"
#include "bench/study/study_runner.hpp"

namespace rotolidar::bench {

int CmdStudy(int argc, char** argv) {
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  OptionParser p("study",
                 "Trade study: expand the sweep of STUDY.yaml (full factorial), run sim + SLAM + evaluation for each "
                 "point as a child `rotolidar demo` process on local cores, and write study.csv, plots/*.svg and "
                 "study.html. Rerunning resumes: finished points (metrics.json present) are skipped.");
  p.AddPositional("STUDY", "study YAML (docs/studies.md)");
  p.Add("out", "", "-", "output folder (default runs/study_<STUDY file name>)");
  p.Add("jobs", std::to_string(hw), "-", "points run at once (default: this machine's hardware threads)");
  p.AddFlag("list", "print the points and their folders, run nothing");
  if (int rc = ParseOrHelp(p, argc, argv); rc >= 0) return rc;
  StudyConfig config;
  if (Status s = LoadStudyConfig(p.Get("STUDY"), &config); !s) {
    std::cerr << "error: " << s.message << "\n";
    return 1;
  }
  std::string out = p.Get("out");
  if (out.empty()) out = "runs/study_" + std::filesystem::path(p.Get("STUDY")).stem().string();
  long jobs = 0;
  if (Status s = p.GetInt("jobs", &jobs); !s || jobs < 1) {
    std::cerr << "error: --jobs must be an integer >= 1\n";
    return 2;
  }
  if (p.Flag("list")) {
    std::vector<StudyPoint> points;
    if (Status s = ExpandStudy(config, &points); !s) {
      std::cerr << "error: " << s.message << "\n";
      return 1;
    }
    for (const StudyPoint& pt : points) std::printf("%4zu  %s/points/%s\n", pt.index, out.c_str(), pt.id.c_str());
    return 0;
  }
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  std::filesystem::copy_file(p.Get("STUDY"), out + "/study.yaml", std::filesystem::copy_options::overwrite_existing,
                             ec);
  StudyRunOptions options;
  options.out_dir = out;
  options.jobs = int(jobs);
  options.progress = [](const std::string& line) { std::printf("%s\n", line.c_str()), std::fflush(stdout); };
  StopOnSignals stop;  // Ctrl-C / SIGTERM: start no new point, write what is done
  options.stop = &stop.flag();
  StudyResult result;
  if (Status s = RunStudy(config, options, MakeDemoProcessRunner("", config.slam_config_path), &result); !s) {
    std::cerr << "error: " << s.message << "\n";
    return 1;
  }
  if (Status s = WriteStudyOutputs(config, result, out); !s) {
    std::cerr << "error: " << s.message << "\n";
    return 1;
  }
  std::printf("[study] %s: %zu points (%zu run, %zu finished earlier, %zu failed)\n  table: %s/study.csv\n  page : %s\n",
              config.name.c_str(), result.points.size(), result.ran, result.resumed, result.failed, out.c_str(),
              std::filesystem::absolute(out + "/study.html").c_str());
  if (stop.signal() != 0) {
    std::fprintf(stderr, "[study] stopped by %s: %zu points not run; the same command resumes the study\n",
                 stop.name(), result.not_run);
    return 128 + stop.signal();
  }
  return result.failed > 0 ? 1 : 0;
}

}  // namespace rotolidar::bench
