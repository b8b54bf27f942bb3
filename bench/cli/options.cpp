#include "bench/cli/options.hpp"
#include "core/util/log.hpp"

#include <algorithm>
#include <cstdlib>
#include <iomanip>
#include <iostream>

namespace rotolidar::bench {

int Fail(const Status& s, int code) {
  std::cerr << "error: " << s.message << "\n";
  return code;
}

int Usage(const std::string& message) {
  std::cerr << "error: " << message << "\n";
  return 2;
}

void OptionParser::Add(const std::string& name, const std::string& default_value, const std::string& unit,
                       const std::string& help) {
  specs_.push_back({name, default_value, unit, help, false});
  values_[name] = default_value;
}

void OptionParser::AddFlag(const std::string& name, const std::string& help) {
  specs_.push_back({name, "false", "-", help, true});
  values_[name] = "false";
}

void OptionParser::AddPositional(const std::string& name, const std::string& help, const std::string& default_value) {
  positionals_.push_back({name, default_value, "-", help, false});
  values_[name] = default_value;
}

Status OptionParser::Parse(int argc, char** argv) {
  size_t next_positional = 0;
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      help_ = true;
      return Status::Ok();
    }
    if (arg.rfind("--", 0) == 0) {
      std::string name = arg.substr(2), value;
      const size_t eq = name.find('=');
      if (eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
      }
      const OptionSpec* spec = nullptr;
      for (const auto& s : specs_) spec = s.name == name ? &s : spec;
      if (!spec) return Status::Error(command_ + ": unknown option --" + name + " (see --help)");
      if (spec->is_flag) {
        value = eq == std::string::npos ? "true" : value;
      } else if (eq == std::string::npos) {
        if (i + 1 >= argc) return Status::Error(command_ + ": option --" + name + " needs a value");
        value = argv[++i];
      }
      values_[name] = value;
      set_[name] = true;
    } else if (next_positional < positionals_.size()) {
      values_[positionals_[next_positional].name] = arg;
      set_[positionals_[next_positional++].name] = true;
    } else {
      return Status::Error(command_ + ": unexpected argument '" + arg + "' (see --help)");
    }
  }
  for (size_t i = next_positional; i < positionals_.size(); ++i)
    if (positionals_[i].default_value.empty())
      return Status::Error(command_ + ": missing argument " + positionals_[i].name + " (see --help)");
  return Status::Ok();
}

void OptionParser::PrintHelp(std::ostream& os) const {
  os << "usage: rotolidar " << command_;
  for (const auto& p : positionals_) os << " " << (p.default_value.empty() ? p.name : "[" + p.name + "]");
  os << " [options]\n\n" << summary_ << "\n\n";
  if (!positionals_.empty()) {
    os << "arguments:\n";
    for (const auto& p : positionals_) os << "  " << std::left << std::setw(24) << p.name << p.help << "\n";
    os << "\n";
  }
  // Columns wide enough for the longest entry, so a long default never runs into its unit.
  size_t name_w = 26, default_w = 20, unit_w = 9;
  for (const auto& s : specs_) {
    name_w = std::max(name_w, s.name.size() + 4);
    default_w = std::max(default_w, s.default_value.size() + 2);
    unit_w = std::max(unit_w, s.unit.size() + 2);
  }
  const int nw = int(name_w), dw = int(default_w), uw = int(unit_w);
  os << std::left << "  " << std::setw(nw) << "option" << std::setw(dw) << "default" << std::setw(uw) << "unit"
     << "description\n";
  os << "  " << std::string(name_w + default_w + unit_w + 40, '-') << "\n";
  for (const auto& s : specs_) {
    os << "  " << std::setw(nw) << ("--" + s.name) << std::setw(dw)
       << (s.default_value.empty() ? "(none)" : s.default_value) << std::setw(uw) << (s.unit.empty() ? "-" : s.unit)
       << s.help << "\n";
  }
  os << "  " << std::setw(nw) << "--help" << std::setw(dw) << "" << std::setw(uw) << "-" << "show this table\n";
}

std::string OptionParser::Get(const std::string& name) const {
  const auto it = values_.find(name);
  ROTOLIDAR_CHECK(it != values_.end(), "option --" << name << " was never declared");
  return it->second;
}

Status OptionParser::GetDouble(const std::string& name, double* value) const {
  const std::string text = Get(name);
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') return Status::Error(command_ + ": --" + name + ": not a number: '" + text + "'");
  *value = v;
  return Status::Ok();
}

Status OptionParser::GetInt(const std::string& name, long* value) const {
  const std::string text = Get(name);
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0') return Status::Error(command_ + ": --" + name + ": not an integer: '" + text + "'");
  *value = v;
  return Status::Ok();
}

int ParseOrHelp(OptionParser& parser, int argc, char** argv) {
  if (Status s = parser.Parse(argc, argv); !s) {
    std::cerr << "error: " << s.message << "\n";
    return 2;
  }
  if (parser.help_requested()) {
    parser.PrintHelp(std::cout);
    return 0;
  }
  return -1;
}

}  // namespace rotolidar::bench
