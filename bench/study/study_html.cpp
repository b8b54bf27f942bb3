// study.html and the writing of a study's outputs (study_report.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "bench/report/svg_plot.hpp"
#include "bench/study/study_ranking.hpp"
#include "bench/study/study_report.hpp"
#include "bench/study/study_seeds.hpp"

namespace rotolidar::bench {
namespace {

/// A CSV line split at commas outside quotes (StudyCsv's own quoting).
std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"' && quoted && i + 1 < line.size() && line[i + 1] == '"') fields.back() += '"', ++i;
    else if (c == '"') quoted = !quoted;
    else if (c == ',' && !quoted) fields.emplace_back();
    else fields.back() += c;
  }
  return fields;
}

const char* kStyle =
    "body{font-family:sans-serif;margin:1.5em;color:#222}"
    "table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}"
    "th{background:#eee;position:sticky;top:0}td:first-child{text-align:left}tr.failed{background:#fdd}"
    "tr.best{background:#dfd;font-weight:bold}.warn{color:#842;font-size:13px}"
    ".figs{display:flex;flex-wrap:wrap;gap:12px}.note{color:#555;font-size:13px}";

/// The table rows of study.csv as HTML (the same numbers, so page and CSV cannot disagree).
void WriteTable(const StudyResult& result, std::ostringstream& os) {
  std::istringstream csv(StudyCsv(result));
  std::string line;
  std::getline(csv, line);
  os << "<table><tr>";
  for (const std::string& h : SplitCsv(line)) os << "<th>" << XmlEscape(h) << "</th>";
  os << "<th>log</th></tr>\n";
  for (const StudyPointResult& r : result.points) {
    std::getline(csv, line);
    const std::vector<std::string> fields = SplitCsv(line);
    os << "<tr" << (r.state == PointState::kFailed ? " class=\"failed\"" : "") << ">";
    const std::string dir = "points/" + r.point.id;
    os << "<td><a href=\"" << XmlEscape(dir) << "/\">" << XmlEscape(fields[0]) << "</a></td>";
    for (size_t i = 1; i < fields.size(); ++i) os << "<td>" << XmlEscape(fields[i]) << "</td>";
    os << "<td><a href=\"" << XmlEscape(dir) << "/log.txt\">log</a>";
    if (r.state == PointState::kFailed) os << " " << XmlEscape(r.message);
    os << "</td></tr>\n";
  }
  os << "</table>\n";
}

/// Median, p90 and worst ATE over each group's seeds (only when some group has more than one seed).
void WriteSeedTable(const StudyResult& result, std::ostringstream& os) {
  const std::vector<SeedStatistics> stats = StudySeedStatistics(result);
  if (std::none_of(stats.begin(), stats.end(), [](const SeedStatistics& s) { return s.seeds > 1; })) return;
  os << "<h2>Over seeds</h2>\n<p class=\"note\">ATE RMSE over the seeds of each group (points that differ only in "
        "seed); nearest-rank percentiles; failed runs are counted, not averaged away. All metrics: "
        "<a href=\"study_seeds.csv\">study_seeds.csv</a>.</p>\n<table><tr><th>group</th><th>seeds</th>"
        "<th>failed</th><th>median [m]</th><th>p90 [m]</th><th>worst [m]</th><th>p90 / median</th></tr>\n";
  char buf[256];
  for (const SeedStatistics& s : stats) {
    if (s.metric != "ate_rmse_m") continue;
    os << "<tr" << (s.failed > 0 ? " class=\"failed\"" : "") << "><td>" << XmlEscape(s.group) << "</td>";
    if (s.values == 0) {
      os << "<td>" << s.seeds << "</td><td>" << s.failed << "</td><td colspan=\"4\">no value</td></tr>\n";
      continue;
    }
    std::snprintf(buf, sizeof(buf), "<td>%zu</td><td>%zu</td><td>%.4f</td><td>%.4f</td><td>%.4f</td><td>%.2f</td>",
                  s.seeds, s.failed, s.median, s.p90, s.max, s.median > 0.0 ? s.p90 / s.median : 0.0);
    os << buf << "</tr>\n";
  }
  os << "</table>\n";
}

/// "mean ± sd [min, max]" of one metric over a group's seeds.
std::string SpreadCell(const MetricSpread& s) {
  if (s.n == 0) return "no value";
  char buf[160];
  std::snprintf(buf, sizeof(buf), "%.4g &plusmn; %.2g [%.4g, %.4g]", s.mean, s.sd, s.min, s.max);
  return buf;
}

/// The configurations ranked per partition (study_ranking.hpp), the best of each marked.
void WriteRanking(const StudyConfig& config, const StudyResult& result, std::ostringstream& os) {
  const std::vector<RankedGroup> ranked = RankStudyGroups(result, config.rank_by);
  if (ranked.empty()) return;
  os << "<h2>Ranking</h2>\n<p class=\"note\">Points that differ only in seed form a configuration; configurations "
        "are ranked within each scene/carrier by the sum of their ranks on ";
  for (size_t m = 0; m < config.rank_by.size(); ++m)
    os << (m ? ", " : "") << "<b>" << XmlEscape(config.rank_by[m]) << "</b> ("
       << (HigherIsBetter(config.rank_by[m]) ? "higher" : "lower") << " is better)";
  os << " (means over seeds); a configuration with a failed seed ranks last. Cells: mean &plusmn; standard deviation "
        "[min, max] over seeds. t: Welch's t of the first metric against the best; |t| &lt; 2 means the seeds do "
        "not separate it from the best.</p>\n";
  std::string partition = "\x01";
  for (const RankedGroup& g : ranked) {
    if (g.partition != partition) {
      if (partition != "\x01") os << "</table>\n";
      partition = g.partition;
      os << "<h3>" << XmlEscape(partition) << "</h3>\n<table><tr><th>rank</th><th>configuration</th><th>seeds</th>"
         << "<th>failed</th><th>score</th>";
      for (const std::string& m : config.rank_by) os << "<th>" << XmlEscape(m) << "</th>";
      os << "<th>t vs best</th></tr>\n";
    }
    os << "<tr" << (g.rank == 1 ? " class=\"best\"" : g.failed > 0 ? " class=\"failed\"" : "") << "><td>" << g.rank
       << (g.rank == 1 ? " &#9733; best" : "") << "</td><td>" << XmlEscape(g.design) << "</td><td>" << g.seeds
       << "</td><td>" << g.failed << "</td><td>" << g.score << "</td>";
    for (const MetricSpread& s : g.metrics) os << "<td>" << SpreadCell(s) << "</td>";
    char t[32];
    std::snprintf(t, sizeof(t), "%.2f", g.t_vs_best);
    os << "<td>" << (g.rank == 1 ? "&mdash;" : std::isfinite(g.t_vs_best) ? t : "n/a") << "</td></tr>\n";
  }
  os << "</table>\n";
}

const char* kHostLoadWarning =
    "<p class=\"warn\">&#9888; Time columns (slam_median_scan_ms, slam_realtime_factor, sim_wall_s, slam_wall_s, "
    "runtime_s) measure the host as much as the configuration: how many points ran at once (--jobs), what else the "
    "machine was doing, and on Slurm which node a task landed on. Compare them only between points run together on "
    "one otherwise idle machine; the accuracy and coverage columns do not depend on the host.</p>\n";

}  // namespace

std::string StudyHtml(const StudyConfig& config, const StudyResult& result, const std::vector<StudyFigure>& figures) {
  std::ostringstream os;
  os << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>study " << XmlEscape(config.name)
     << "</title><style>" << kStyle << "</style></head><body>\n";
  os << "<h1>Study: " << XmlEscape(config.name) << "</h1>\n<p class=\"note\">" << result.points.size() << " points ("
     << result.ran << " run now, " << result.resumed << " finished earlier, " << result.failed << " failed)";
  if (!config.source_path.empty()) os << "; study file " << XmlEscape(config.source_path);
  os << ". Table: <a href=\"study.csv\">study.csv</a>. Failed points are left out of the plots; points that "
        "differ only in seed are averaged (error bars: standard deviation). Metric definitions: docs/studies.md, "
        "docs/metrics.md.</p>\n<div class=\"figs\">\n";
  for (const StudyFigure& f : figures) os << "<figure>" << f.svg << "</figure>\n";
  os << "</div>\n" << kHostLoadWarning;
  WriteRanking(config, result, os);
  WriteSeedTable(result, os);
  os << "<h2>Points</h2>\n" << kHostLoadWarning;
  WriteTable(result, os);
  os << "</body></html>\n";
  return os.str();
}

Status WriteStudyOutputs(const StudyConfig& config, const StudyResult& result, const std::string& out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir + "/plots", ec);
  if (ec) return Status::Error(out_dir + "/plots: cannot create: " + ec.message());
  if (Status s = WriteFileAtomically(out_dir + "/study.csv", StudyCsv(result)); !s) return s;
  if (Status s = WriteFileAtomically(out_dir + "/study_seeds.csv", StudySeedsCsv(StudySeedStatistics(result))); !s)
    return s;
  const std::vector<StudyFigure> figures = StudyFigures(config, result);
  for (const StudyFigure& f : figures)
    if (Status s = WriteFileAtomically(out_dir + "/plots/" + f.file_name, f.svg); !s) return s;
  return WriteFileAtomically(out_dir + "/study.html", StudyHtml(config, result, figures));
}

}  // namespace rotolidar::bench
