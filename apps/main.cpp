// nec: one motion language for skeletons of any shape. Dispatches subcommands.
#include "command_line.h"
#include "commands.h"

#include "nec/assets/asset_reader.h"
#include "nec/motion/error.h"
#include "nec/train/heap.h"

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

struct Subcommand {
  const char* name;
  int (*run)(int, char**);
  const char* summary;
};

constexpr Subcommand kSubcommands[] = {
    {"demo", nec::app::run_demo, "run the pipeline on built-in data (zoo + Debian's CMU files) into out/demo"},
    {"info", nec::app::run_info, "print a BVH file's skeleton, channels, frames and diameter"},
    {"convert", nec::app::run_convert, "read a BVH file and write it back (optionally in another Euler order)"},
    {"normalize", nec::app::run_normalize, "apply the unified preprocessing and write the result"},
    {"augment", nec::app::run_augment, "write a rig-augmented copy (rest pose, bone lengths, joints)"},
    {"prepare", nec::app::run_prepare, "turn folders of BVH (+ captions) into a dataset cache"},
    {"zoo", nec::app::run_zoo, "write procedural creatures with captioned clips (BVH + caption sidecars)"},
    {"text", nec::app::run_text, "word vectors: import GloVe once, joint-name similarity, nearest words"},
    {"view", nec::app::run_view, "show BVH clips in a self-contained HTML player, or a PNG strip of frames"},
    {"retrieve", nec::app::run_retrieve, "find motions of a cache by text, or captions for a motion (trained evaluator)"},
    {"train", nec::app::run_train, "train a model: owo (skeleton encoder), tat (tokenizer), evaluator (text-motion), gpt (text to tokens) or diffusion"},
    {"eval", nec::app::run_eval, "evaluate a trained model: owo (skeleton encoder on unseen skeletons)"},
    {"encode", nec::app::run_encode, "turn a BVH clip into motion tokens with a trained tokenizer"},
    {"decode", nec::app::run_decode, "decode motion tokens onto any skeleton, as BVH"},
    {"transfer", nec::app::run_transfer, "move a clip onto another skeleton (encode + decode)"},
    {"generate", nec::app::run_generate, "motion from text for any skeleton (trained GPT + tokenizer), as BVH"},
    {"serve", nec::app::run_serve, "the local studio: a web page to generate, transfer and search on your rig"},
    {"worker", nec::app::run_worker, "run commands sent on stdin, keeping models loaded between them (nec serve's)"},
};

void print_overview() {
  fmt::print("usage: nec COMMAND [arguments] [options]\n\ncommands:\n");
  for (const Subcommand& c : kSubcommands) fmt::print("  {:<10} {}\n", c.name, c.summary);
  fmt::print("\n`nec COMMAND --help` shows a command's arguments and defaults.\n"
             "exit codes: 0 ok, 1 bad input, 2 usage error\n");
}

}  // namespace

int nec::app::run_subcommand(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    print_overview();
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  for (const Subcommand& c : kSubcommands) {
    if (name != c.name) continue;
    try {
      return c.run(argc - 2, argv + 2);
    } catch (const nec::app::UsageError& e) {
      fmt::print(stderr, "nec {}: {}\n(see `nec {} --help`)\n", name, e.what(), name);
      return 2;
    } catch (const nec::InputError& e) {
      fmt::print(stderr, "nec: error: {}\n", e.what());
      return 1;
    } catch (const std::exception& e) {
      fmt::print(stderr, "nec: error: {}\n", e.what());
      return 1;
    }
  }
  fmt::print(stderr, "nec: unknown command '{}'\n\n", name);
  print_overview();
  return 2;
}

int main(int argc, char** argv) {
  nec::train::keep_large_allocations_in_heap();
  nec::assets::register_asset_formats();  // every command reads FBX / glTF / Collada / .x as well as BVH
  const int code = nec::app::run_subcommand(argc, argv);
  // Every command has closed its outputs by now. Leaving without the static destructors of libtorch and
  // the libraries it loads, or freeing the models, saves about 80 ms of a 1-s command.
  std::fflush(nullptr);
  std::_Exit(code);
}
