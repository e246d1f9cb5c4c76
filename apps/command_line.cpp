// Command-line parsing for the nec subcommands.
#include "command_line.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sstream>

namespace nec::app {

CommandLine::CommandLine(std::string command, std::string summary)
    : command_(std::move(command)), summary_(std::move(summary)) {}

void CommandLine::positional(std::string name, std::string help, bool required, bool many) {
  positional_specs_.push_back({std::move(name), std::move(help), required, many});
}

void CommandLine::option(std::string name, std::string value_name, std::string default_value, std::string help,
                         bool required) {
  values_[name] = default_value;
  options_.push_back({std::move(name), std::move(value_name), std::move(default_value), std::move(help), required, false});
}

void CommandLine::flag(std::string name, std::string help) {
  flags_[name] = false;
  options_.push_back({std::move(name), "", "", std::move(help), false, true});
}

void CommandLine::example(std::string line) { examples_.push_back(std::move(line)); }

void CommandLine::epilogue(std::string text) { epilogue_ = std::move(text); }

const CommandLine::Option* CommandLine::find(const std::string& name) const {
  for (const Option& o : options_) {
    if (o.name == name) return &o;
  }
  return nullptr;
}

bool CommandLine::parse(int argc, char** argv) {
  std::vector<std::string> loose;
  std::map<std::string, bool> given;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      std::fputs(usage().c_str(), stdout);
      return false;
    }
    if (arg.size() > 1 && arg[0] == '-' && !(arg.size() > 1 && (std::isdigit(static_cast<unsigned char>(arg[1])) || arg[1] == '.'))) {
      std::string inline_value;
      bool has_inline = false;
      const size_t eq = arg.find('=');
      if (arg.rfind("--", 0) == 0 && eq != std::string::npos) {
        inline_value = arg.substr(eq + 1);
        arg = arg.substr(0, eq);
        has_inline = true;
      }
      const Option* o = find(arg);
      if (!o) throw UsageError("unknown option '" + arg + "'");
      if (o->is_flag) {
        if (has_inline) throw UsageError("option '" + arg + "' takes no value");
        flags_[arg] = true;
        continue;
      }
      if (!has_inline) {
        if (i + 1 >= argc) throw UsageError("option '" + arg + "' needs a value (" + o->value_name + ")");
        inline_value = argv[++i];
      }
      values_[arg] = inline_value;
      given[arg] = true;
      continue;
    }
    loose.push_back(arg);
  }
  for (const Option& o : options_) {
    if (o.required && !given[o.name]) throw UsageError("missing required option " + o.name + " " + o.value_name);
  }
  size_t next = 0;
  for (const Positional& p : positional_specs_) {
    std::vector<std::string>& into = positional_values_[p.name];
    if (p.many) {
      while (next < loose.size()) into.push_back(loose[next++]);
    } else if (next < loose.size()) {
      into.push_back(loose[next++]);
    }
    if (p.required && into.empty()) throw UsageError("missing " + p.name);
  }
  if (next < loose.size()) throw UsageError("unexpected argument '" + loose[next] + "'");
  return true;
}

std::string CommandLine::usage() const {
  std::ostringstream out;
  out << "usage: " << command_;
  for (const Positional& p : positional_specs_) {
    out << ' ' << (p.required ? "" : "[") << p.name << (p.many ? " ..." : "") << (p.required ? "" : "]");
  }
  if (!options_.empty()) out << " [options]";
  out << "\n\n" << summary_ << "\n";
  if (!positional_specs_.empty()) {
    out << "\narguments:\n";
    for (const Positional& p : positional_specs_) out << "  " << p.name << "\n      " << p.help << "\n";
  }
  if (!options_.empty()) {
    out << "\noptions:\n";
    for (const Option& o : options_) {
      out << "  " << o.name << (o.is_flag ? "" : " " + o.value_name) << "\n      " << o.help;
      if (o.required) {
        out << " (required)";
      } else if (!o.is_flag) {
        out << " (default: " << (o.default_value.empty() ? "none" : o.default_value) << ")";
      }
      out << "\n";
    }
    out << "  -h, --help\n      show this help\n";
  }
  if (!examples_.empty()) {
    out << "\nexamples:\n";
    for (const std::string& e : examples_) out << "  " << e << "\n";
  }
  if (!epilogue_.empty()) out << "\n" << epilogue_;
  return out.str();
}

const std::string& CommandLine::value(const std::string& name) const {
  const auto it = values_.find(name);
  if (it == values_.end()) throw std::logic_error("CommandLine: undeclared option " + name);
  return it->second;
}

bool CommandLine::declared(const std::string& name) const { return find(name) != nullptr; }

int CommandLine::integer(const std::string& name) const {
  const std::string& text = value(name);
  int out = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  if (ec != std::errc() || ptr != text.data() + text.size()) {
    throw UsageError("option " + name + " needs a whole number, got '" + text + "'");
  }
  return out;
}

double CommandLine::number(const std::string& name) const {
  const std::string& text = value(name);
  double out = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(out)) {
    throw UsageError("option " + name + " needs a number, got '" + text + "'");
  }
  return out;
}

bool CommandLine::is_set(const std::string& flag_name) const {
  const auto it = flags_.find(flag_name);
  if (it == flags_.end()) throw std::logic_error("CommandLine: undeclared flag " + flag_name);
  return it->second;
}

std::vector<std::string> CommandLine::list(const std::string& name) const {
  std::vector<std::string> items;
  const std::string& text = value(name);
  for (size_t begin = 0; begin <= text.size();) {
    const size_t comma = std::min(text.find(',', begin), text.size());
    if (comma > begin) items.push_back(text.substr(begin, comma - begin));
    begin = comma + 1;
  }
  return items;
}

UpAxis CommandLine::up_axis(const std::string& name) const {
  const std::string& text = value(name);
  if (text == "auto") return UpAxis::Auto;
  if (text == "y") return UpAxis::Y;
  if (text == "z") return UpAxis::Z;
  throw UsageError(name + " must be auto, y or z, got '" + text + "'");
}

const std::vector<std::string>& CommandLine::positionals(const std::string& name) const {
  static const std::vector<std::string> kNone;
  const auto it = positional_values_.find(name);
  return it == positional_values_.end() ? kNone : it->second;
}

const std::string& CommandLine::positional_value(const std::string& name) const {
  const auto& values = positionals(name);
  if (values.empty()) throw std::logic_error("CommandLine: no value for " + name);
  return values.front();
}

int run_nested(const std::string& usage, const std::string& list_title, const std::string& kind,
               const std::vector<NestedCommand>& commands, int argc, char** argv) {
  if (argc < 1 || std::strcmp(argv[0], "--help") == 0 || std::strcmp(argv[0], "-h") == 0) {
    fmt::print("usage: {}\n\n{}:\n", usage, list_title);
    size_t width = 0;
    for (const NestedCommand& c : commands) width = std::max(width, std::string(c.name).size());
    for (const NestedCommand& c : commands) fmt::print("  {:<{}} {}\n", c.name, width, c.summary);
    size_t words_end = 0;  // after the first three words: "nec train MODEL"
    for (int word = 0; word < 3 && words_end != std::string::npos; ++word) words_end = usage.find(' ', words_end + 1);
    const std::string command = usage.substr(0, words_end);
    fmt::print("\n`{} --help` shows its options and defaults.\n", command);
    return argc < 1 ? 2 : 0;
  }
  std::string known;
  for (const NestedCommand& c : commands) {
    known += (known.empty() ? "" : ", ") + std::string(c.name);
    if (std::strcmp(argv[0], c.name) == 0) return c.run(argc - 1, argv + 1);
  }
  throw UsageError("unknown " + kind + " '" + argv[0] + "' (known: " + known + ")");
}

}  // namespace nec::app
