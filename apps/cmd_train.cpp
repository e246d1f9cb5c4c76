// nec train MODEL ...: one subcommand per trainable model.
#include "command_line.h"
#include "commands.h"

namespace nec::app {

int run_train(int argc, char** argv) {
  return run_nested("nec train MODEL --config CFG.json --data CACHE --out CKPT [options]", "models", "model",
                    {{"owo", run_train_owo, "pretrain the OwO skeleton encoder on the skeletons of dataset caches"},
                     {"stance", run_train_stance, "the stance of a rig given without motion, from its skeleton (rigs of caches)"},
                     {"tat", run_train_tat, "train the topology-agnostic tokenizer with a frozen OwO encoder"},
                     {"evaluator", run_train_evaluator, "train the text-motion evaluator (retrieval and metrics)"},
                     {"gpt", run_train_gpt, "train the text-to-token transformer on a tokenizer's codes"},
                     {"diffusion", run_train_diffusion, "train the motion diffusion model (--stage pose, then motion)"}},
                    argc, argv);
}

}  // namespace nec::app
