// The `nec` subcommands. Each takes the arguments after its name and returns
// the exit code: 0 ok, 1 bad input; usage problems throw UsageError (exit 2).
#pragma once

namespace nec::app {

int run_info(int argc, char** argv);
int run_convert(int argc, char** argv);
int run_normalize(int argc, char** argv);
int run_augment(int argc, char** argv);
int run_prepare(int argc, char** argv);
int run_view(int argc, char** argv);
int run_zoo(int argc, char** argv);
int run_demo(int argc, char** argv);
int run_text(int argc, char** argv);
int run_train_tokenizer(int argc, char** argv);  // nec text train-tokenizer
int run_pieces(int argc, char** argv);           // nec text pieces
int run_train(int argc, char** argv);      // nec train MODEL ...: dispatches to run_train_<model>
int run_train_owo(int argc, char** argv);  // nec train owo
int run_eval(int argc, char** argv);       // nec eval MODEL ...: dispatches to run_eval_<model>
int run_eval_owo(int argc, char** argv);   // nec eval owo
int run_train_stance(int argc, char** argv);  // nec train stance
int run_eval_stance(int argc, char** argv);   // nec eval stance
int run_encode(int argc, char** argv);
int run_decode(int argc, char** argv);
int run_transfer(int argc, char** argv);
int run_train_tat(int argc, char** argv);
int run_train_evaluator(int argc, char** argv);  // nec train evaluator
int run_eval_recon(int argc, char** argv);
int run_eval_transfer(int argc, char** argv);
int run_eval_retrieval(int argc, char** argv);  // nec eval retrieval
int run_eval_t2m(int argc, char** argv);        // nec eval t2m
int run_retrieve(int argc, char** argv);        // nec retrieve
int run_train_gpt(int argc, char** argv);       // nec train gpt
int run_train_diffusion(int argc, char** argv); // nec train diffusion
int run_generate(int argc, char** argv);        // nec generate
int run_serve(int argc, char** argv);           // nec serve
int run_worker(int argc, char** argv);          // nec worker

// Runs `nec ARGV[1] ...` (argv[0] is the program), reporting errors as the binary does: the exit code.
int run_subcommand(int argc, char** argv);

}  // namespace nec::app
