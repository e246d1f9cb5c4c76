// nec eval NAME ...: one subcommand per kind of evaluation.
#include "command_line.h"
#include "commands.h"

namespace nec::app {

int run_eval(int argc, char** argv) {
  return run_nested("nec eval NAME [arguments] [options]", "evaluations", "evaluation",
                    {{"owo", run_eval_owo, "OwO skeleton encoder on skeletons it never saw: LCA accuracy, offsets, tree rebuild"},
                     {"stance", run_eval_stance, "stance network: predicted against true stance bone directions, per dataset and pose"},
                     {"recon", run_eval_recon, "tokenizer reconstruction error on clips it never trained on"},
                     {"transfer", run_eval_transfer, "transferred clips against their sources: speed, heading, feet, bones"},
                     {"t2m", run_eval_t2m, "generated motion against real motion: R-Precision, FID, Diversity, Coverage, ..."},
                     {"retrieval", run_eval_retrieval, "evaluator R-Precision: mixed, within plan, creature words masked, floor"}},
                    argc, argv);
}

}  // namespace nec::app
