// nec eval MODEL ...: one subcommand per kind of evaluation (owo, recon).
#include "command_line.h"
#include "commands.h"

#include <fmt/format.h>

#include <cstring>
#include <string>

namespace nec::app {
namespace {

struct EvalCommand {
  const char* name;
  int (*run)(int, char**);  // nullptr: announced, not built yet
  const char* summary;
};

// An evaluation is one line here.
constexpr EvalCommand kEvalCommands[] = {
    {"owo", run_eval_owo, "OwO skeleton encoder on skeletons it never saw: LCA accuracy, offsets, tree rebuild"},
    {"recon", run_eval_recon, "tokenizer reconstruction error on clips it never trained on"},
};

void print_eval_overview() {
  fmt::print("usage: nec eval MODEL --model CKPT --data CACHE [options]\n\nevaluations:\n");
  for (const EvalCommand& c : kEvalCommands) {
    fmt::print("  {:<6} {}{}\n", c.name, c.summary, c.run ? "" : " (not built yet)");
  }
  fmt::print("\n`nec eval MODEL --help` shows its options and defaults.\n");
}

}  // namespace

int run_eval(int argc, char** argv) {
  if (argc < 1 || std::strcmp(argv[0], "--help") == 0 || std::strcmp(argv[0], "-h") == 0) {
    print_eval_overview();
    return argc < 1 ? 2 : 0;
  }
  std::string known;
  for (const EvalCommand& c : kEvalCommands) {
    known += (known.empty() ? "" : ", ") + std::string(c.name);
    if (std::strcmp(argv[0], c.name) != 0) continue;
    if (!c.run) throw UsageError(std::string("evaluation '") + c.name + "' is not built yet");
    return c.run(argc - 1, argv + 1);
  }
  throw UsageError(std::string("unknown evaluation '") + argv[0] + "' (known: " + known + ")");
}

}  // namespace nec::app
