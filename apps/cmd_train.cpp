// nec train MODEL ...: one subcommand per trainable model (owo, tat).
#include "command_line.h"
#include "commands.h"

#include <fmt/format.h>

#include <cstring>
#include <string>

namespace nec::app {
namespace {

struct ModelCommand {
  const char* name;
  int (*run)(int, char**);  // nullptr: announced, not built yet
  const char* summary;
};

// A model's trainer is one line here.
constexpr ModelCommand kTrainCommands[] = {
    {"owo", run_train_owo, "pretrain the OwO skeleton encoder on the skeletons of dataset caches"},
    {"tat", run_train_tat, "train the topology-agnostic tokenizer with a frozen OwO encoder"},
};

void print_train_overview() {
  fmt::print("usage: nec train MODEL --config CFG.json --data CACHE --out CKPT [options]\n\nmodels:\n");
  for (const ModelCommand& c : kTrainCommands) {
    fmt::print("  {:<6} {}{}\n", c.name, c.summary, c.run ? "" : " (not built yet)");
  }
  fmt::print("\n`nec train MODEL --help` shows a model's options and defaults.\n");
}

}  // namespace

int run_train(int argc, char** argv) {
  if (argc < 1 || std::strcmp(argv[0], "--help") == 0 || std::strcmp(argv[0], "-h") == 0) {
    print_train_overview();
    return argc < 1 ? 2 : 0;
  }
  std::string known;
  for (const ModelCommand& c : kTrainCommands) {
    known += (known.empty() ? "" : ", ") + std::string(c.name);
    if (std::strcmp(argv[0], c.name) != 0) continue;
    if (!c.run) throw UsageError(std::string("training '") + c.name + "' is not built yet");
    return c.run(argc - 1, argv + 1);
  }
  throw UsageError(std::string("unknown model '") + argv[0] + "' (known: " + known + ")");
}

}  // namespace nec::app
