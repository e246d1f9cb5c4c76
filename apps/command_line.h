// A small declarative command-line parser for the `nec` subcommands.
//
//   CommandLine cli("nec convert", "Read a BVH file and write it back.");
//   cli.positional("IN.bvh", "input file");
//   cli.option("-o", "OUT.bvh", "", "output file (required)");
//   cli.option("--order", "ORDER", "keep", "Euler order to write: XYZ ... ZYX, or keep");
//   if (!cli.parse(argc, argv)) return 0;        // --help was printed
//   std::string out = cli.value("-o");
//
// Usage problems throw UsageError; main turns them into exit code 2.
#pragma once

#include "nec/corpus/preprocess.h"

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace nec::app {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CommandLine {
 public:
  CommandLine(std::string command, std::string summary);

  // A positional argument; `many` takes all remaining positionals (at least one if required).
  void positional(std::string name, std::string help, bool required = true, bool many = false);
  // An option taking a value; an empty default with `required` means it must be given.
  void option(std::string name, std::string value_name, std::string default_value, std::string help,
              bool required = false);
  void flag(std::string name, std::string help);
  void example(std::string line);
  // Text printed last in --help, e.g. the fields of a config file.
  void epilogue(std::string text);

  // Returns false when --help was asked for (usage is printed to stdout).
  bool parse(int argc, char** argv);
  std::string usage() const;

  const std::string& value(const std::string& name) const;
  bool declared(const std::string& name) const;  // an option or flag of this name exists
  int integer(const std::string& name) const;
  double number(const std::string& name) const;
  bool is_set(const std::string& flag_name) const;
  // A comma-separated option value, without empty items.
  std::vector<std::string> list(const std::string& name) const;
  // An up-axis option: auto, y or z.
  UpAxis up_axis(const std::string& name) const;
  const std::vector<std::string>& positionals(const std::string& name) const;
  const std::string& positional_value(const std::string& name) const;

 private:
  struct Option {
    std::string name, value_name, default_value, help;
    bool required = false;
    bool is_flag = false;
  };
  struct Positional {
    std::string name, help;
    bool required = true, many = false;
  };
  const Option* find(const std::string& name) const;

  std::string command_, summary_;
  std::vector<Option> options_;
  std::vector<Positional> positional_specs_;
  std::vector<std::string> examples_;
  std::string epilogue_;
  std::map<std::string, std::string> values_;
  std::map<std::string, bool> flags_;
  std::map<std::string, std::vector<std::string>> positional_values_;
};

// A command under a command, e.g. `nec train owo`.
struct NestedCommand {
  const char* name;          // e.g. "owo"
  int (*run)(int, char**);   // gets the arguments after the name
  const char* summary;
};

// Runs the command of `commands` named by argv[0]. With no argument or --help
// prints `usage`, then each command under `list_title` (exit 2 / 0); an unknown
// name throws UsageError "unknown <kind> 'x' (known: a, b)".
int run_nested(const std::string& usage, const std::string& list_title, const std::string& kind,
               const std::vector<NestedCommand>& commands, int argc, char** argv);

}  // namespace nec::app
