#pragma once
// A small, strict command-line parser for the rotolidar subcommands: `--name value` and `--flag`, a help table
// with defaults and units, and errors that name the option. No global state.
#include <map>
#include <string>
#include <vector>

#include "core/util/status.hpp"

namespace rotolidar::bench {

struct OptionSpec {
  std::string name;           ///< without the leading "--"
  std::string default_value;  ///< "" = none; flags use "false"
  std::string unit;           ///< e.g. "s", "m", "rad/s", "-" when unitless
  std::string help;
  bool is_flag = false;
};

class OptionParser {
 public:
  OptionParser(std::string command, std::string summary) : command_(std::move(command)), summary_(std::move(summary)) {}

  void Add(const std::string& name, const std::string& default_value, const std::string& unit, const std::string& help);
  void AddFlag(const std::string& name, const std::string& help);
  /// Adds a positional argument (required unless its default is non-empty).
  void AddPositional(const std::string& name, const std::string& help, const std::string& default_value = "");

  /// Parses argv (after the subcommand). `--help`/`-h` sets help_requested(). Unknown options, missing values
  /// and missing positionals are errors naming the option.
  Status Parse(int argc, char** argv);
  bool help_requested() const { return help_; }
  void PrintHelp(std::ostream& os) const;

  std::string Get(const std::string& name) const;
  bool Flag(const std::string& name) const { return Get(name) == "true"; }
  /// Numeric accessors: fail with a message naming the option when the value is not a number.
  Status GetDouble(const std::string& name, double* value) const;
  Status GetInt(const std::string& name, long* value) const;
  bool IsSet(const std::string& name) const { return set_.count(name) > 0; }

 private:
  std::string command_, summary_;
  std::vector<OptionSpec> specs_;
  std::vector<OptionSpec> positionals_;
  std::map<std::string, std::string> values_;
  std::map<std::string, bool> set_;
  bool help_ = false;
};

/// Parses argv; prints the help table for --help. Returns -1 to go on, otherwise the exit code to return
/// (0 after help, 2 after a usage error, whose message goes to stderr).
int ParseOrHelp(OptionParser& parser, int argc, char** argv);

/// The subcommands' exit paths: "error: <message>" on stderr, then the exit code to return from the command.
int Fail(const Status& s, int code = 1);  ///< the command failed (1 unless given)
int Usage(const std::string& message);     ///< the command line was wrong (2)

}  // namespace rotolidar::bench
