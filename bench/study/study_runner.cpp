#include "bench/study/study_runner.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

namespace rotolidar::bench {
namespace fs = std::filesystem;
namespace {

/// A value as a folder-name fragment: [A-Za-z0-9._-] kept, anything else '_'.
std::string Sanitize(const std::string& value) {
  std::string out = value;
  for (char& c : out)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
  return out;
}

std::string FormatDouble(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

/// The sweep as (axis name, value names, setter) triples, in expansion order (outermost first).
struct Axis {
  std::string name;
  std::vector<std::string> values;
  std::function<void(size_t, StudyPoint*)> apply;
};

std::vector<Axis> SweptAxes(const StudyConfig& c) {
  const StudySweep& s = c.sweep;
  std::vector<Axis> axes;
  auto add = [&axes](std::string name, std::vector<std::string> values, std::function<void(size_t, StudyPoint*)> f) {
    if (!values.empty()) axes.push_back({std::move(name), std::move(values), std::move(f)});
  };
  std::vector<std::string> v;
  for (const StudyVariant& x : s.variants) v.push_back(x.name);
  add("variant", v, [&s](size_t i, StudyPoint* p) { p->sim = s.variants[i].sim, p->variant = s.variants[i].name; });
  add("scene", s.scenes, [&s](size_t i, StudyPoint* p) { p->sim.scene = s.scenes[i]; });
  v.clear();
  for (sim::CarrierType x : s.carriers) v.push_back(sim::CarrierTypeName(x));
  add("carrier", v, [&s](size_t i, StudyPoint* p) { p->sim.carrier.type = s.carriers[i]; });
  v.clear();
  for (sim::MotorAxis x : s.axes) v.push_back(sim::MotorAxisName(x));
  add("axis", v, [&s](size_t i, StudyPoint* p) { p->sim.rig_model.motor.axis = s.axes[i]; });
  v.clear();
  for (sim::MotorProfileType x : s.profiles) v.push_back(sim::ToString(x));
  add("profile", v, [&s](size_t i, StudyPoint* p) { p->sim.motor.profile.type = s.profiles[i]; });
  v.clear();
  for (double x : s.motor_speed_radps) v.push_back(FormatDouble(x));
  add("speed", v, [&s](size_t i, StudyPoint* p) { p->sim.motor.profile.speed_radps = s.motor_speed_radps[i]; });
  v.clear();
  for (uint64_t x : s.seeds) v.push_back(std::to_string(x));
  add("seed", v, [&s](size_t i, StudyPoint* p) { p->sim.seed = s.seeds[i]; });
  return axes;
}

std::string ReadText(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return f ? ss.str() : std::string();
}

/// Finished = metrics.json parses and the point's recorded config is the one it would get now.
bool IsFinished(const std::string& dir, const std::string& config_text) {
  std::vector<double> unused;
  return ReadText(dir + "/sim_config.yaml") == config_text && ReadPointMetrics(dir + "/metrics.json", &unused);
}

double ReadRecordedRuntime(const std::string& dir) {
  const nlohmann::json j = nlohmann::json::parse(ReadText(dir + "/point_status.json"), nullptr, false);
  if (j.is_object() && j.contains("runtime_s") && j["runtime_s"].is_number()) return j["runtime_s"].get<double>();
  return kStudyNaN;
}

Status WriteStatus(const std::string& dir, const StudyPointResult& r) {
  nlohmann::json j = {{"id", r.point.id}, {"state", PointStateName(r.state)}, {"exit_code", r.exit_code},
                      {"message", r.message}};
  if (std::isfinite(r.runtime_s)) j["runtime_s"] = r.runtime_s;
  return WriteFileAtomically(dir + "/point_status.json", j.dump(2) + "\n");
}

/// Runs one pending point and fills its row.
void RunOne(const PointRunner& runner, const std::string& dir, StudyPointResult* r) {
  const auto t0 = std::chrono::steady_clock::now();
  PointRunOutcome outcome;
  try {
    outcome = runner(r->point, dir);
  } catch (const std::exception& e) {
    outcome = {-1, std::string("runner threw: ") + e.what()};
  }
  r->runtime_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r->exit_code = outcome.exit_code;
  r->message = outcome.message;
  Status read = ReadPointMetrics(dir + "/metrics.json", &r->metrics);
  if (outcome.exit_code == 0 && read) {
    r->state = PointState::kRan;
  } else {
    r->state = PointState::kFailed;
    if (r->message.empty()) r->message = outcome.exit_code != 0 ? "exit status " + std::to_string(outcome.exit_code)
                                                                : "no usable metrics.json: " + read.message;
    // A failed point must not look finished to the next run.
    std::error_code ec;
    fs::remove(dir + "/metrics.json", ec);
  }
  if (Status s = WriteStatus(dir, *r); !s && r->message.empty()) r->message = s.message;
}

}  // namespace

std::string PointConfigText(const StudyPoint& point) {
  YAML::Emitter out;
  sim::EmitSimConfig(out, point.sim);
  return std::string(out.c_str()) + "\n";
}

const char* PointStateName(PointState state) {
  switch (state) {
    case PointState::kRan: return "ran";
    case PointState::kResumed: return "resumed";
    case PointState::kFailed: return "failed";
  }
  return "unknown";
}

Status ExpandStudy(const StudyConfig& config, std::vector<StudyPoint>* points) {
  const std::vector<Axis> axes = SweptAxes(config);
  const size_t n = config.sweep.NumPoints();
  std::vector<StudyPoint> out;
  std::set<std::string> ids;
  for (size_t k = 0; k < n; ++k) {
    StudyPoint p;
    p.index = k;
    p.sim = config.base;
    size_t rest = k;  // mixed-radix digits, the last axis fastest
    std::vector<size_t> digit(axes.size());
    for (size_t a = axes.size(); a-- > 0;) digit[a] = rest % axes[a].values.size(), rest /= axes[a].values.size();
    for (size_t a = 0; a < axes.size(); ++a) {  // outermost first: the variant replaces the whole config
      axes[a].apply(digit[a], &p);
      p.swept.emplace_back(axes[a].name, axes[a].values[digit[a]]);
      p.id += (p.id.empty() ? "" : "__") + axes[a].name + "-" + Sanitize(axes[a].values[digit[a]]);
    }
    if (p.id.empty()) p.id = "base";
    std::string why;
    if (!p.sim.Validate(&why)) return Status::Error("study point " + p.id + ": invalid sim config: " + why);
    if (!ids.insert(p.id).second) return Status::Error("study point " + p.id + ": two points share this name");
    out.push_back(std::move(p));
  }
  *points = std::move(out);
  return Status::Ok();
}

Status WriteFileAtomically(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << content;
    f.flush();
    if (!f) return Status::Error(tmp + ": write failed");
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) return Status::Error(path + ": rename failed: " + ec.message());
  return Status::Ok();
}

Status ReadPointMetrics(const std::string& path, std::vector<double>* values) {
  if (!fs::exists(path)) return Status::Error(path + ": missing");
  const nlohmann::json j = nlohmann::json::parse(ReadText(path), nullptr, false);
  if (j.is_discarded() || !j.is_object()) return Status::Error(path + ": not a JSON object");
  values->assign(StudyMetrics().size(), kStudyNaN);
  for (size_t i = 0; i < StudyMetrics().size(); ++i) {
    for (const std::string& pointer : StudyMetrics()[i].json_pointers) {
      const nlohmann::json::json_pointer ptr(pointer);
      if (!j.contains(ptr)) continue;
      if (j.at(ptr).is_number()) (*values)[i] = j.at(ptr).get<double>();
      break;
    }
  }
  return Status::Ok();
}

Status PrepareStudyPoints(const std::vector<StudyPoint>& points, const std::string& out_dir, StudyResult* res,
                          std::vector<size_t>* pending) {
  for (const StudyPoint& p : points) {
    StudyPointResult r;
    r.point = p;
    r.metrics.assign(StudyMetrics().size(), kStudyNaN);
    const std::string dir = out_dir + "/points/" + p.id, text = PointConfigText(p);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return Status::Error(dir + ": cannot create: " + ec.message());
    if (IsFinished(dir, text)) {
      r.state = PointState::kResumed;
      if (Status s = ReadPointMetrics(dir + "/metrics.json", &r.metrics); !s) return s;
      r.runtime_s = ReadRecordedRuntime(dir);
    } else {
      fs::remove(dir + "/metrics.json", ec);  // stale results of an older config
      if (Status s = WriteFileAtomically(dir + "/sim_config.yaml", text); !s) return s;
      pending->push_back(res->points.size());
    }
    res->points.push_back(std::move(r));
  }
  return Status::Ok();
}

void FinishStudyResult(StudyResult* res) {
  res->ran = res->resumed = res->failed = res->not_run = 0;
  for (StudyPointResult& r : res->points) {
    for (size_t i = 0; i < StudyMetrics().size(); ++i)  // the one metric the study measures itself
      if (StudyMetrics()[i].name == "runtime_s") r.metrics[i] = r.runtime_s;
    res->ran += r.state == PointState::kRan;
    res->resumed += r.state == PointState::kResumed;
    res->failed += r.state == PointState::kFailed;
    res->not_run += r.state == PointState::kFailed && r.message == "not run: the study was stopped";
  }
}

Status RunStudy(const StudyConfig& config, const StudyRunOptions& options, const PointRunner& runner,
                StudyResult* result) {
  std::vector<StudyPoint> points;
  if (Status s = ExpandStudy(config, &points); !s) return s;
  StudyResult res;
  std::vector<size_t> pending;
  if (Status s = PrepareStudyPoints(points, options.out_dir, &res, &pending); !s) return s;
  const size_t total = res.points.size();
  std::mutex mutex;
  size_t done = total - pending.size();
  auto say = [&options](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  say("[study] " + std::to_string(total) + " points, " + std::to_string(done) + " finished earlier, " +
      std::to_string(pending.size()) + " to run");
  if (done > 0) say("[study] " + std::to_string(done) + "/" + std::to_string(total) + " points done");
  std::atomic<size_t> next{0};
  auto worker = [&]() {
    for (size_t k = next++; k < pending.size(); k = next++) {
      StudyPointResult& r = res.points[pending[k]];
      if (options.stop && *options.stop) {
        r.message = "not run: the study was stopped";
        continue;
      }
      const std::string dir = options.out_dir + "/points/" + r.point.id;
      RunOne(runner, dir, &r);
      std::lock_guard<std::mutex> lock(mutex);
      ++done;
      if (r.state == PointState::kFailed)
        say("[study] point " + r.point.id + " FAILED (" + r.message + "); log: " + dir + "/log.txt");
      say("[study] " + std::to_string(done) + "/" + std::to_string(total) + " points done");
    }
  };
  const int hw = std::max(1, int(std::thread::hardware_concurrency()));
  const size_t jobs = std::min<size_t>(pending.size(), size_t(options.jobs > 0 ? options.jobs : hw));
  std::vector<std::thread> threads;
  for (size_t t = 0; t < jobs; ++t) threads.emplace_back(worker);
  for (std::thread& t : threads) t.join();
  FinishStudyResult(&res);
  *result = std::move(res);
  return Status::Ok();
}

}  // namespace rotolidar::bench
