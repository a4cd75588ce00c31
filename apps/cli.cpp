#include "cli.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "isowave/core/error.h"

namespace isowave::cli {
namespace {

[[noreturn]] void usage_error(const std::string& message) { throw Error(ErrorKind::InvalidArgument, message); }

// An argument that is an option rather than a value (a negative number is a value).
bool looks_like_option(const std::string& arg) {
  return arg.size() > 1 && arg[0] == '-' && !std::isdigit(static_cast<unsigned char>(arg[1])) && arg[1] != '.';
}

const OptionSpec* find_option(const CommandSpec& spec, const std::string& name) {
  for (const OptionSpec& option : spec.options)
    if (option.name == name) return &option;
  return nullptr;
}

// `text` on one line: newlines and runs of spaces become one space.
std::string one_line(const std::string& text) {
  std::string line;
  for (const char c : text)
    if (!((c == ' ' || c == '\n') && !line.empty() && line.back() == ' ')) line += c == '\n' ? ' ' : c;
  return line;
}

// `text` with its single line breaks as spaces: blank lines separate paragraphs.
std::string paragraphs(const std::string& text) {
  std::string out = text;
  for (std::size_t i = 0; i < out.size(); ++i)
    if (out[i] == '\n' && (i + 1 == out.size() || out[i + 1] != '\n') && (i == 0 || out[i - 1] != '\n')) out[i] = ' ';
  return out;
}

// `text` broken at spaces into lines of at most kHelpColumns (a word longer
// than that stays whole), continued after `indent` spaces; its own line
// breaks are kept. Each line ends with '\n'.
std::string wrap(const std::string& text, std::size_t indent) {
  std::string out;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    std::string line;
    for (std::size_t pos = start; pos <= end;) {
      const std::size_t space = std::min(text.find(' ', pos), end);
      const std::string word = text.substr(pos, space - pos);
      const bool has_text = line.find_first_not_of(' ') != std::string::npos && line.size() > indent;
      if (!word.empty() && has_text && line.size() + 1 + word.size() > kHelpColumns) {
        line.erase(line.find_last_not_of(' ') + 1);
        out += line + "\n";
        line = std::string(indent, ' ') + word;
      } else {
        line += (pos == start ? "" : " ") + word;
      }
      pos = space + 1;
    }
    out += line + "\n";
    start = end + 1;
  }
  return out;
}

}  // namespace

Arguments::Arguments(const CommandSpec& spec, const std::vector<std::string>& args) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "-h" || arg == "--help") {
      help_ = true;
      return;
    }
    if (looks_like_option(arg)) {
      std::string name = arg.substr(arg[1] == '-' ? 2 : 1);
      std::string value;
      bool inline_value = false;
      if (const auto eq = name.find('='); eq != std::string::npos) {
        value = name.substr(eq + 1);
        name = name.substr(0, eq);
        inline_value = true;
      }
      if (name == "o") name = "output";
      const OptionSpec* option = find_option(spec, name);
      if (!option) usage_error("unknown option '" + arg + "' (see 'isowave " + spec.name + " --help')");
      if (option->takes_value && !inline_value) {
        if (i + 1 >= args.size() || looks_like_option(args[i + 1]))
          usage_error("option --" + name + " needs a value" +
                      (i + 1 < args.size() ? " (got the option '" + args[i + 1] + "')" : std::string()));
        value = args[++i];
      } else if (!option->takes_value && inline_value) {
        usage_error("option --" + name + " takes no value");
      }
      values_[name] = value;
    } else {
      positional_.push_back(arg);
    }
  }
  const int count = static_cast<int>(positional_.size());
  if (count < spec.min_positional || (spec.max_positional >= 0 && count > spec.max_positional)) {
    usage_error("wrong number of arguments (usage: isowave " + spec.name + " " + one_line(spec.synopsis) + ")");
  }
}

std::string Arguments::get(const std::string& name, const std::string& fallback) const {
  const auto it = values_.find(name);
  return it == values_.end() ? fallback : it->second;
}

std::string Arguments::require(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end()) usage_error("missing required option --" + (name == "output" ? std::string("output (-o)") : name));
  return it->second;
}

int Arguments::get_int(const std::string& name, int fallback, int min, int max) const {
  if (!has(name)) return fallback;
  const std::string text = get(name);
  int value = 0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
  if (result.ec != std::errc() || result.ptr != text.data() + text.size())
    usage_error("--" + name + " expects an integer, got '" + text + "'");
  if (value < min || value > max)
    usage_error("--" + name + " must be in " + std::to_string(min) + ".." + std::to_string(max) + ", got " + text);
  return value;
}

double Arguments::get_double(const std::string& name, double fallback) const {
  if (!has(name)) return fallback;
  const std::string text = get(name);
  double value = 0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
  if (result.ec != std::errc() || result.ptr != text.data() + text.size() || !std::isfinite(value))
    usage_error("--" + name + " expects a number, got '" + text + "'");
  return value;
}

std::vector<double> Arguments::get_double_list(const std::string& name, const std::string& fallback, double min,
                                               double max) const {
  const std::string text = get(name, fallback);
  std::vector<double> values;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t comma = text.find(',', start);
    if (comma == std::string::npos) comma = text.size();
    const std::string item = text.substr(start, comma - start);
    double value = 0;
    const auto result = std::from_chars(item.data(), item.data() + item.size(), value);
    if (item.empty() || result.ec != std::errc() || result.ptr != item.data() + item.size() || !std::isfinite(value) ||
        value < min || value > max) {
      char range[64] = "";
      if (std::isfinite(min) && std::isfinite(max)) std::snprintf(range, sizeof range, " in %g..%g", min, max);
      usage_error("--" + name + " expects numbers" + range + " separated by commas, got '" + text + "'");
    }
    values.push_back(value);
    start = comma + 1;
  }
  return values;
}

void check_outputs(const Arguments& args, const std::vector<std::string>& outputs) {
  namespace fs = std::filesystem;
  std::vector<fs::path> seen;
  for (const std::string& output : outputs) {
    if (output.empty()) usage_error("an output path is empty");
    std::error_code error;
    const fs::path path(output);
    if (fs::is_directory(path, error)) throw Error(ErrorKind::Io, output + ": is a directory");
    const fs::path parent = path.parent_path().empty() ? fs::path(".") : path.parent_path();
    if (!fs::is_directory(parent, error))
      throw Error(ErrorKind::Io, output + ": the directory " + parent.string() + " does not exist");
    if (fs::exists(path, error) && !args.has("force"))
      throw Error(ErrorKind::Io, output + ": already exists (use --force to overwrite)");
    const fs::path canonical = fs::weakly_canonical(path, error);
    for (const fs::path& other : seen)
      if (other == canonical) usage_error(output + ": given for two outputs");
    seen.push_back(canonical);
  }
}

bool has_extension(const std::string& path, const std::string& extension) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == extension;
}

std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += escaped;
      continue;
    }
    out += c;
  }
  return out + "\"";
}

bool print_help_if_requested(const CommandSpec& spec, const Arguments& args) {
  if (!args.help_requested()) return false;
  std::fputs(usage(spec).c_str(), stdout);
  return true;
}

std::string usage(const CommandSpec& spec) {
  std::string text = wrap("usage: isowave " + spec.name + " " + one_line(spec.synopsis), 8) + "\n";
  text += wrap(paragraphs(spec.description), 0);
  if (!spec.options.empty()) text += "\noptions:\n";
  constexpr std::size_t kHelpIndent = 30;
  for (const OptionSpec& option : spec.options) {
    std::string left = "  --" + option.name + (option.takes_value ? " " + option.value_name : "");
    if (option.name == "output") left = "  -o, --output " + option.value_name;
    if (left.size() < kHelpIndent) left.resize(kHelpIndent, ' ');
    else left += "\n" + std::string(kHelpIndent, ' ');
    text += wrap(left + option.help, kHelpIndent);
  }
  text += "  -h, --help                  show this help\n";
  if (!spec.example.empty()) text += "\nExample:\n" + wrap("  isowave " + spec.example, 4);
  return text;
}

}  // namespace isowave::cli
