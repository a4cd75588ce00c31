#pragma once
// Command-line parsing shared by the isowave subcommands: options of the form
// --name VALUE or --name=VALUE, flags, and positional arguments. Usage errors
// are isowave::Error(InvalidArgument); main() prints them on one line.
#include <map>
#include <string>
#include <vector>

namespace isowave::cli {

struct OptionSpec {
  std::string name;        // without the leading dashes, e.g. "levels"
  bool takes_value;        // false for flags
  std::string help;        // one line
  std::string value_name;  // e.g. "L"
};

struct CommandSpec {
  std::string name;
  std::string synopsis;     // e.g. "MESH --levels L [--limit] -o OUT"
  std::string description;  // a few lines
  std::vector<OptionSpec> options;
  int min_positional = 0;
  int max_positional = 0;  // -1 for any number
  std::string example;     // one command line, without "isowave "
};

// Width of the --help text: usage() wraps every line to it.
constexpr std::size_t kHelpColumns = 100;

class Arguments {
 public:
  // Throws Error(InvalidArgument) on an unknown option, a missing value or a
  // wrong number of positional arguments. Sets help_requested() on -h/--help.
  Arguments(const CommandSpec& spec, const std::vector<std::string>& args);

  bool help_requested() const { return help_; }
  bool has(const std::string& name) const { return values_.count(name) != 0; }
  std::string get(const std::string& name, const std::string& fallback = {}) const;
  std::string require(const std::string& name) const;
  int get_int(const std::string& name, int fallback, int min, int max) const;
  double get_double(const std::string& name, double fallback) const;
  // Comma-separated numbers in [min, max], e.g. --iso 1.5,2 or --percents 20,10,5.
  std::vector<double> get_double_list(const std::string& name, const std::string& fallback, double min, double max) const;
  const std::vector<std::string>& positional() const { return positional_; }

 private:
  std::map<std::string, std::string> values_;
  std::vector<std::string> positional_;
  bool help_ = false;
};

// The --help text: synopsis, description, options and the example, every
// line wrapped to kHelpColumns.
std::string usage(const CommandSpec& spec);

// Prints the usage on stdout if -h/--help was given; true if it did (the
// command then returns 0).
bool print_help_if_requested(const CommandSpec& spec, const Arguments& args);

// The option every command that writes files takes.
inline OptionSpec force_option() { return {"force", false, "overwrite existing output files", ""}; }

// Checks, before any work, that each output can be written: not a directory,
// in an existing directory, not an existing file unless --force was given,
// and no two outputs the same file. Throws Error with one line naming it.
void check_outputs(const Arguments& args, const std::vector<std::string>& outputs);

// True if `path` ends in `extension` (".isw", ".svg"), in any case.
bool has_extension(const std::string& path, const std::string& extension);

// `text` as a JSON string literal, quotes included (control characters as \u escapes).
std::string json_string(const std::string& text);

}  // namespace isowave::cli
