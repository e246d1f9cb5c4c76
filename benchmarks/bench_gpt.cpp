// Cost of the GPT on the CPU: a training step, and generation through tokens.
//
//   bench_gpt [--model=GPT_CKPT] [--configs=DIR] [--profile_ops=DIR] [benchmark flags]   # e.g. --benchmark_filter=TrainStep
//
// - BM_GptTrainStep/threads:N: what GptTrainer::step does after its batch is
//   made and its captions read (gpt/synthetic.h): train mode, zero_grad, the
//   condition, token corruption, the teacher-forced forward, gpt_loss,
//   backward, clip, AdamW at the scheduled rate. Model: DIR/gpt_cpu.json with
//   the codebook of DIR/tat_cpu.json's quantizer and skeleton features of
//   OwO's width in DIR/owo_cpu.json (as `nec train gpt` sets them from --tat;
//   64, so 193 features, for the default models); DIR is the repository's
//   configs/ unless given. Inputs: a synthetic batch of batch_size crops and
//   random use-lite backbone outputs, so neither a dataset nor the sentence
//   encoder is read. benchmarks/peer_gpt_step.py makes the same tensors and
//   weights with the same torch random draws, so its first losses must equal
//   the counters loss_step0 and loss_step1; it checks its parameter count
//   against the counter parameters. step_peak_MiB: peak RSS of one step above
//   the RSS before it (after malloc_trim); rss_peak_MiB: the process's peak RSS
//   in it. Model, first losses and memory are made once, at one thread; time
//   is wall clock, cpu_time the process's CPU time (all threads).
// - BM_TextToBvh/samples:N: `nec generate`'s work for a 4-s motion: the
//   caption and skeleton conditions, N samples of 30 token steps (guidance
//   2.5, KV cache), decoded onto a zoo biped and written as BVH. Needs a
//   trained GPT (--model, default models/default/gpt) and its word vectors;
//   skipped without them. Goals: N = 1 < 0.5 s, N = 32 < 3 s on 2 cores.
// - BM_SampleTokens/seconds:S/cache:C: tokens per second of one sample of S
//   seconds (S x 30 / 4 steps; longer than the 47-step window, the sampler
//   slides) with the KV cache (C = 1) or recomputing the window for every
//   step (C = 0). On DIR/gpt_cpu.json's model with random weights (the
//   cost does not depend on them). Goal: with the cache, the cost per token
//   flat in S.
// Each runs 5 repetitions (unless --benchmark_repetitions is given).
#include "nec/gpt/generation.h"
#include "nec/gpt/synthetic.h"
#include "nec/gpt/training.h"
#include "nec/motion/bvh.h"
#include "nec/owo/training.h"
#include "nec/tat/training.h"
#include "nec/text/word_vectors.h"
#include "nec/train/heap.h"
#include "nec/zoo/creature.h"
#include "train_step_support.h"

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
constexpr int kDefaultRepetitions = 5;
constexpr double kFps = 30.0;
constexpr int64_t kDownsampling = 4;
constexpr uint64_t kSeed = 0;        // torch::manual_seed before the synthetic batch and the model (as the peer)
constexpr int64_t kTrainIterations = 3;  // timed training steps per repetition

std::string& model_dir() {
  static std::string dir = std::string(NEC_SOURCE_DIR) + "/models/default/gpt";
  return dir;
}

// gpt_cpu.json with the codebook of tat_cpu.json and OwO's width of owo_cpu.json, as `nec train gpt` takes them
// from the tokenizer it is given.
const nec::gpt::GptTrainConfig& train_config() {
  static const nec::gpt::GptTrainConfig config = [] {
    nec::gpt::GptTrainConfig c = nec::gpt::read_gpt_train_config(nec::bench::configs_dir() + "/gpt_cpu.json");
    const nec::tat::TatTrainConfig tat = nec::tat::read_tat_train_config(nec::bench::configs_dir() + "/tat_cpu.json");
    c.model.codebook_layers = tat.model.quantizer.layers;
    c.model.codebook_size = tat.model.quantizer.codebook_size;
    c.model.skeleton_dim = nec::owo::read_owo_training_config(nec::bench::configs_dir() + "/owo_cpu.json").encoder.dim;
    c.validate();
    return c;
  }();
  return config;
}

// ---- Training step ----

// The model, its optimizer and one synthetic batch, made once (at one thread) and kept across repetitions and
// thread counts.
struct Trainee {
  nec::gpt::SyntheticGptBatch inputs;
  nec::gpt::TokenGpt model{nullptr};
  std::unique_ptr<torch::optim::AdamW> optimizer;
  int64_t steps = 0;  // steps taken (learning-rate schedule position)
  nec::bench::StepRecord record;

  Trainee() {
    const nec::gpt::GptTrainConfig& config = train_config();
    const int threads = torch::get_num_threads();
    torch::set_num_threads(1);
    torch::manual_seed(kSeed);
    inputs = nec::gpt::synthetic_gpt_batch(config.model, config.batch_size, config.caption_dropout);
    model = nec::gpt::TokenGpt(config.model);
    optimizer = nec::train::make_adamw(model->parameters(), config.optimizer);
    record = nec::bench::record_first_steps(model->parameters(), [&] { return step(); });
    torch::set_num_threads(threads);
  }

  // One step of the peer-comparable loop at the next schedule position.
  double step() { return nec::gpt::synthetic_gpt_train_step(*model, *optimizer, inputs, train_config(), ++steps); }
};

void BM_GptTrainStep(benchmark::State& state) {
  static Trainee trainee;
  const int threads = torch::get_num_threads();
  torch::set_num_threads(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(trainee.step());
  nec::bench::profile_ops_if_asked("BM_GptTrainStep/threads:" + std::to_string(state.range(0)), [&] { trainee.step(); }, 1);
  torch::set_num_threads(threads);  // the other benchmarks run on every core
  nec::bench::set_step_counters(state, trainee.record);
}

// A zoo biped's skeleton as a BVH file, the target of BM_TextToBvh.
const std::string& biped_file() {
  static const std::string path = [] {
    const std::string file = (fs::temp_directory_path() / ("nec_bench_gpt_biped_" + std::to_string(::getpid()) + ".bvh")).string();
    const nec::zoo::Creature creature = nec::zoo::make_creature(nec::zoo::BodyPlan::Biped, 1);
    nec::write_bvh(file, creature.skeleton, nec::Motion::rest(creature.skeleton, 2, kFps));
    return file;
  }();
  return path;
}

void BM_TextToBvh(benchmark::State& state) {
  static std::optional<nec::gpt::GeneratorSession> session;
  if (!session) {
    if (!fs::exists(fs::path(model_dir()) / "config.json") || !fs::exists(nec::text::default_word_vectors_path())) {
      state.SkipWithError("no trained GPT (--model) or no word vectors (nec text import-glove)");
      return;
    }
    session.emplace(nec::gpt::open_generator(model_dir(), ""));
  }
  const int samples = static_cast<int>(state.range(0));
  const std::string out = (fs::temp_directory_path() / ("nec_bench_gpt_" + std::to_string(::getpid()))).string();
  nec::gpt::SamplingOptions sampling;
  for (auto _ : state) {
    const nec::PreparedClip target = nec::tat::prepare_for_model(biped_file(), session->fps(), nec::UpAxis::Auto);
    const std::vector<at::Tensor> codes =
        nec::gpt::generate_codes(*session, target, {{"a person walks forward", 30}}, samples, sampling);
    for (size_t i = 0; i < codes.size(); ++i) {
      nec::tat::decode_onto(session->tokenizer, session->token_file(codes[i], "a person walks forward"), target,
                            biped_file(), {}, out + "_" + std::to_string(i) + ".bvh");
    }
  }
  for (int i = 0; i < samples; ++i) fs::remove(out + "_" + std::to_string(i) + ".bvh");
  state.counters["motions_per_s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsIterationInvariantRate);
}

// configs/gpt_cpu.json's model for a 4 x 256 codebook, random weights, eval mode, with one condition.
struct RandomGpt {
  nec::gpt::TokenGpt model{nullptr};
  nec::gpt::GptCondition condition, unconditioned;

  RandomGpt() {
    nec::gpt::GptConfig config = nec::gpt::read_gpt_train_config(nec::bench::configs_dir() + "/gpt_cpu.json").model;
    config.codebook_layers = 4;
    config.codebook_size = 256;
    config.skeleton_dim = 64;
    torch::manual_seed(0);
    model = nec::gpt::TokenGpt(config);
    model->eval();
    c10::InferenceMode inference;
    // The sentence encoder's outputs for a caption of 10 pieces (the config's backbone is use-lite).
    nec::text::TextBatch caption;
    caption.encoder_features = torch::randn({1, 10, nec::text::kUseLiteWidth});
    caption.encoder_sentence = torch::nn::functional::normalize(torch::randn({1, nec::text::kUseLiteWidth}));
    caption.mask = torch::ones({1, 10}, torch::kBool);
    const at::Tensor skeleton = torch::randn({1, nec::gpt::skeleton_feature_width(64)});
    condition = model->condition(caption, skeleton, {});
    unconditioned = model->unconditioned(skeleton);
  }
};

void BM_SampleTokens(benchmark::State& state) {
  static RandomGpt gpt;
  const int64_t steps = state.range(0) * static_cast<int64_t>(kFps) / kDownsampling;
  const bool cached = state.range(1) == 1;
  nec::gpt::SamplingOptions sampling;
  nec::gpt::SequenceLength length;
  length.steps = steps;
  c10::InferenceMode inference;
  for (auto _ : state) {
    if (cached) {
      benchmark::DoNotOptimize(nec::gpt::sample_codes(*gpt.model, gpt.condition, &gpt.unconditioned, {}, length, sampling));
      continue;
    }
    // Without the cache: every step reads its whole window again (greedy codes; the draws cost the same).
    const int64_t window = gpt.model->config().max_steps - 1, r = gpt.model->config().codebook_layers;
    const nec::gpt::GptCondition both = gpt.condition;
    at::Tensor sequence = torch::zeros({1, 0, r}, torch::kInt64);
    for (int64_t t = 0; t < steps; ++t) {
      nec::gpt::KvCache cache;
      const int64_t keep = std::min(sequence.size(1), window);
      const at::Tensor h = gpt.model->start(both, cache, sequence.narrow(1, sequence.size(1) - keep, keep));
      at::Tensor codes = torch::zeros({1, r}, torch::kInt64);
      for (int64_t layer = 0; layer < r; ++layer) {
        const at::Tensor logits = gpt.model->layer_logits(h, layer, codes.narrow(1, 0, layer));
        codes.select(1, layer).copy_(logits.narrow(1, 0, gpt.model->config().codebook_size).argmax(1));
      }
      sequence = torch::cat({sequence, codes.unsqueeze(1)}, 1);
    }
    benchmark::DoNotOptimize(sequence);
  }
  state.counters["tokens_per_s"] = benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

BENCHMARK(BM_GptTrainStep)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->Iterations(kTrainIterations)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()            // time: wall clock
    ->MeasureProcessCPUTime()  // cpu_time: all threads of the process
    ->ComputeStatistics("min", nec::bench::smallest)
    ->ComputeStatistics("max", nec::bench::largest)
    ->DisplayAggregatesOnly(true);  // the JSON output keeps every repetition
BENCHMARK(BM_TextToBvh)->ArgName("samples")->Arg(1)->Arg(32)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SampleTokens)
    ->ArgNames({"seconds", "cache"})
    ->ArgsProduct({{4, 16, 64}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

int main(int argc, char** argv) {
  nec::train::keep_large_allocations_in_heap();  // as nec does
  std::vector<char*> args;
  bool repetitions = false;
  for (int i = 0; i < argc; ++i) {
    if (std::strncmp(argv[i], "--model=", 8) == 0) {
      model_dir() = argv[i] + 8;
      continue;
    }
    if (nec::bench::take_step_flag(argv[i])) continue;
    if (std::strncmp(argv[i], "--benchmark_repetitions", 23) == 0) repetitions = true;
    args.push_back(argv[i]);
  }
  std::string default_repetitions = "--benchmark_repetitions=" + std::to_string(kDefaultRepetitions);
  if (!repetitions) args.push_back(default_repetitions.data());
  torch::set_num_threads(static_cast<int>(std::thread::hardware_concurrency()));  // every core (2 here)
  try {
    const nec::gpt::GptTrainConfig& config = train_config();
    std::fprintf(stderr, "bench_gpt: training step on %lld x %lld codes, batch %lld\n",
                 static_cast<long long>(config.model.codebook_layers),
                 static_cast<long long>(config.model.codebook_size), static_cast<long long>(config.batch_size));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_gpt: %s\n", e.what());
    return 1;
  }
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
