// Cost of the text-motion evaluator on the CPU (configs/evaluator_cpu.json):
// one training step, caption encoding, motion embedding and a retrieval query
// over a 10,000-clip index.
//
//   bench_evaluator [--configs=DIR] [--profile_ops=DIR] [benchmark flags]   # e.g. --benchmark_filter=TrainStep
//
// Model: DIR/evaluator_cpu.json with joint_embedding_dim = encoder.dim of
// DIR/owo_cpu.json (as `nec train evaluator` sets it from the OwO
// checkpoint); DIR is the repository's configs/ unless given.
// - BM_EvaluatorTrainStep/joints:J/threads:N: what EvaluatorTrainer::step
//   does after its batch is made (evaluator/synthetic.h): forward (train
//   mode), contrastive loss, zero_grad, backward, clip_grad_norm_, AdamW at
//   the scheduled learning rate. Inputs are a synthetic batch (B =
//   batch_size, T = window_frames, skeletons of J - J / 4 to J joints, T / 2
//   to T real frames): random Θ, random joint embeddings in place of OwO's,
//   random per-piece features and unit sentence vectors in place of the
//   sentence encoder's. Needs neither the sentence encoder nor a dataset.
//   benchmarks/peer_evaluator_step.py makes the same tensors with the same
//   torch random draws, so its first losses must equal the counters
//   loss_step0 and loss_step1 here. Counters: parameters (the peer checks
//   its count against it), step_peak_MiB (peak RSS of one step above the RSS
//   before it, after malloc_trim) and rss_peak_MiB (the process's peak RSS
//   during that step); model, first losses and memory are made once per J,
//   at one thread.
// The other benchmarks share one setup (the config's caption reader: with
// use-lite, the sentence encoder) and are skipped when it cannot be made.
// - BM_EncodeCaptions/threads:N: the config's caption reader + text encoder
//   (eval mode) on batches of 32 corpus-like captions; counter captions_per_s.
//   With the use-lite backbone that is the sentence encoder and the head on
//   it; with pieces, the piece model is trained at start on those captions
//   (BPE, at most 300 pieces) and the word vectors are random 100-d rows for
//   their words, written to a temporary folder.
// - BM_EncodeSentences/threads:N: the sentence encoder alone on those batches.
// - BM_EmbedMotions/joints:J/threads:N: OwO joint embeddings of the batch's
//   skeletons (configs/owo_cpu.json's encoder, untrained, without names) +
//   the motion encoder on 32 random 120-frame clips (4 s at 30 fps); counter clips_per_s.
// - BM_RetrievalQuery/threads:N/captions:C: one caption embedded and ranked
//   against 10,000 unit-length clip embeddings (RetrievalIndex::nearest_clips,
//   k = 5), the index in memory; time per query. With C = 3 each clip also has
//   three captions and the query is blended with them (`nec retrieve`'s
//   default --caption-weight 0.5: the query through the sentence encoder too).
//   Goal: < 20 ms on 2 cores.
// Each runs 5 repetitions (unless --benchmark_repetitions is given) and
// reports mean, median, stddev, min and max of wall-clock and process CPU time.
#include "nec/evaluator/evaluator.h"
#include "nec/evaluator/retrieval_index.h"
#include "nec/evaluator/synthetic.h"
#include "nec/evaluator/training.h"
#include "nec/owo/training.h"
#include "nec/owo/graph.h"
#include "nec/owo/pretrain.h"
#include "nec/tat/inference.h"
#include "nec/tat/synthetic.h"
#include "nec/text/caption_text.h"
#include "nec/text/piece_model.h"
#include "nec/text/sentence_encoder.h"
#include "nec/text/text_encoder.h"
#include "nec/text/word_vectors.h"
#include "nec/train/heap.h"
#include "nec/train/optimizer.h"
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
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
constexpr int kDefaultRepetitions = 5;
constexpr int64_t kBatch = 32;
constexpr int64_t kClipFrames = 120;
constexpr int64_t kIndexClips = 10000;
constexpr uint64_t kSeed = 0;        // torch::manual_seed before the step's inputs and model (as the peer)
constexpr int64_t kTrainIterations22 = 3, kTrainIterations100 = 1;  // timed steps per repetition (as the peer)

// The encoder width of DIR/owo_cpu.json: the joint embeddings the motion encoder reads.
int64_t owo_dim() { return nec::owo::read_owo_training_config(nec::bench::configs_dir() + "/owo_cpu.json").encoder.dim; }

// evaluator_cpu.json, joint embeddings as wide as owo_cpu.json's encoder.
const nec::evaluator::EvaluatorTrainConfig& train_config() {
  static const nec::evaluator::EvaluatorTrainConfig config = [] {
    nec::evaluator::EvaluatorTrainConfig c =
        nec::evaluator::read_evaluator_train_config(nec::bench::configs_dir() + "/evaluator_cpu.json");
    c.model.motion.joint_embedding_dim = owo_dim();
    c.validate();
    return c;
  }();
  return config;
}

std::vector<std::string> captions() {
  std::vector<std::string> out;
  for (const char* creature : {"a dog", "a spider", "a person", "a dragon", "a snake", "someone", "a horse", "a bird"}) {
    for (const char* verb : {"walks", "runs", "trots", "crawls", "turns", "jumps", "waves both hands", "bows politely"}) {
      for (const char* how : {"forward", "to the left", "slowly and wearily", "quickly in a circle", "like an elderly person"}) {
        out.push_back(std::string(creature) + " " + verb + " " + how);
      }
    }
  }
  return out;
}

// The caption reader, word vectors and evaluator (configs/evaluator_cpu.json) every benchmark shares.
struct Setup {
  fs::path folder;
  nec::text::CaptionReader reader;
  std::optional<nec::text::WordVectors> vectors;
  nec::evaluator::Evaluator model{nullptr};
  nec::owo::OwoPretrainer owo{nullptr};

  Setup() {
    folder = fs::temp_directory_path() / ("nec_bench_evaluator_" + std::to_string(::getpid()));
    fs::create_directories(folder);
    nec::text::PieceTrainOptions options;
    options.vocab_size = 300;
    nec::text::train_piece_model(captions(), options, (folder / "spm.model").string());
    std::set<std::string> words;
    for (const std::string& caption : captions()) {
      for (const std::string& word : nec::text::caption_words(caption)) words.insert(word);
    }
    std::mt19937 rng(0);
    std::normal_distribution<float> normal(0.f, 0.4f);
    std::vector<float> rows;
    for (size_t i = 0; i < words.size() * 100; ++i) rows.push_back(normal(rng));
    nec::text::write_word_vectors((folder / "words.bin").string(), {words.begin(), words.end()}, rows, 100);
    vectors.emplace(nec::text::WordVectors::load((folder / "words.bin").string()));

    nec::evaluator::EvaluatorTrainConfig config = train_config();
    nec::owo::OwoConfig owo_config;
    owo_config.dim = owo_dim();
    owo_config.name_dim = 0;
    torch::manual_seed(0);
    owo = nec::owo::OwoPretrainer(owo_config, nec::owo::PretrainConfig{});
    owo->eval();
    reader = nec::text::CaptionReader::for_training(config.model.text, (folder / "spm.model").string());
    model = nec::evaluator::Evaluator(config.model);
    model->eval();
  }
  ~Setup() { fs::remove_all(folder); }
};

Setup& setup() {
  static Setup s;
  return s;
}

// The shared setup, or null after marking the benchmark skipped with the reason (e.g. no sentence encoder).
Setup* setup_or_skip(benchmark::State& state) {
  try {
    return &setup();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

// ---- Training step ----

// A model, its optimizer and one batch, kept across repetitions and thread counts.
struct Trainee {
  nec::evaluator::ContrastiveBatch inputs;
  nec::evaluator::Evaluator model{nullptr};
  std::unique_ptr<torch::optim::AdamW> optimizer;
  int64_t steps = 0;  // steps taken (learning-rate schedule position)
  nec::bench::StepRecord record;
};

// One step of the peer-comparable loop (evaluator/synthetic.h) at the next schedule position.
double train_step(Trainee& t) {
  return nec::evaluator::synthetic_evaluator_train_step(*t.model, *t.optimizer, t.inputs, train_config(), ++t.steps);
}

// The trainee of a joint count, made on first use (at one thread, from the
// seed) and kept for every later benchmark of that size.
Trainee& trainee(int64_t joints) {
  static std::map<int64_t, std::unique_ptr<Trainee>> made;
  std::unique_ptr<Trainee>& slot = made[joints];
  if (slot) return *slot;
  slot = std::make_unique<Trainee>();
  Trainee& t = *slot;
  const nec::evaluator::EvaluatorTrainConfig& config = train_config();
  const int threads = torch::get_num_threads();
  torch::set_num_threads(1);
  torch::manual_seed(kSeed);
  t.inputs = nec::evaluator::synthetic_contrastive_batch(config.batch_size, config.data.window_frames, joints,
                                                         config.model.motion.joint_embedding_dim);
  t.model = nec::evaluator::Evaluator(config.model);
  t.optimizer = nec::train::make_adamw(t.model->parameters(), config.optimizer);
  t.record = nec::bench::record_first_steps(t.model->parameters(), [&] { return train_step(t); });
  torch::set_num_threads(threads);
  return t;
}

void BM_EvaluatorTrainStep(benchmark::State& state) {
  const int64_t joints = state.range(0);
  torch::set_num_threads(static_cast<int>(state.range(1)));
  Trainee& t = trainee(joints);
  for (auto _ : state) benchmark::DoNotOptimize(train_step(t));
  nec::bench::profile_ops_if_asked("BM_EvaluatorTrainStep/joints:" + std::to_string(joints) + "/threads:" +
                                       std::to_string(state.range(1)),
                                   [&] { train_step(t); }, 1);
  const nec::evaluator::EvaluatorTrainConfig& config = train_config();
  state.SetItemsProcessed(state.iterations() * config.batch_size);  // (clip, caption) pairs
  nec::bench::set_step_counters(state, t.record);
}

// ---- Captions, motions, retrieval ----

// The next kBatch captions of `all`, going round.
std::vector<std::string> next_batch(const std::vector<std::string>& all, size_t& next) {
  std::vector<std::string> batch;
  for (int64_t i = 0; i < kBatch; ++i) batch.push_back(all[next++ % all.size()]);
  return batch;
}

void BM_EncodeCaptions(benchmark::State& state) {
  torch::set_num_threads(static_cast<int>(state.range(0)));
  Setup* s = setup_or_skip(state);
  if (s == nullptr) return;
  const std::vector<std::string> all = captions();
  size_t next = 0;
  for (auto _ : state) {
    const std::vector<std::string> batch = next_batch(all, next);
    c10::InferenceMode inference;
    const at::Tensor out = s->model->embed_text(s->reader.read(batch, &*s->vectors, "bench"));
    benchmark::DoNotOptimize(out.data_ptr());
  }
  state.counters["captions_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kBatch), benchmark::Counter::kIsRate);
}

// The pretrained sentence encoder (text/sentence_encoder.h) on the same batches: pieces, graph, sentence vectors.
void BM_EncodeSentences(benchmark::State& state) {
  torch::set_num_threads(static_cast<int>(state.range(0)));
  static std::optional<nec::text::SentenceEncoder> encoder;
  if (!encoder) {
    if (!fs::exists(nec::text::default_sentence_encoder_dir() + "/model.json")) {
      state.SkipWithError("no sentence encoder: run scripts/setup_sentence_encoder.sh");
      return;
    }
    encoder.emplace(nec::text::default_sentence_encoder_dir());
  }
  const std::vector<std::string> all = captions();
  size_t next = 0;
  for (auto _ : state) {
    const std::vector<std::string> batch = next_batch(all, next);
    c10::InferenceMode inference;
    const nec::text::SentenceEncoding out = (*encoder)->encode(batch);
    benchmark::DoNotOptimize(out.sentence.data_ptr());
  }
  state.counters["captions_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kBatch), benchmark::Counter::kIsRate);
}

// One random skeleton of `joints` joints (parents before children).
nec::Skeleton random_skeleton(int64_t joints, std::mt19937& rng) {
  std::normal_distribution<double> offset(0.0, 0.1);
  nec::Skeleton skeleton;
  for (int64_t j = 0; j < joints; ++j) {
    const int parent = j == 0 ? -1 : static_cast<int>(std::uniform_int_distribution<int64_t>(0, j - 1)(rng));
    skeleton.add_joint("Joint" + std::to_string(j), parent,
                       j == 0 ? nec::Vec3::Zero() : nec::Vec3(offset(rng), offset(rng), offset(rng)),
                       j == 0 ? nec::ChannelLayout::position_rotations(nec::EulerOrder::ZXY)
                              : nec::ChannelLayout::rotations(nec::EulerOrder::ZXY));
  }
  return skeleton;
}

void BM_EmbedMotions(benchmark::State& state) {
  torch::set_num_threads(static_cast<int>(state.range(1)));
  Setup* s = setup_or_skip(state);
  if (s == nullptr) return;
  const int64_t joints = state.range(0);
  std::mt19937 rng(1);
  std::vector<nec::Skeleton> skeletons;
  for (int64_t i = 0; i < kBatch; ++i) skeletons.push_back(random_skeleton(joints, rng));
  const std::vector<std::vector<std::string>> names(kBatch, std::vector<std::string>(joints, "joint"));
  torch::manual_seed(2);
  const at::Tensor features = nec::tat::random_features(kBatch, kClipFrames, joints);
  const at::Tensor joint_mask = torch::ones({kBatch, joints}, torch::kBool);
  const at::Tensor frame_mask = torch::ones({kBatch, kClipFrames}, torch::kBool);
  for (auto _ : state) {
    c10::InferenceMode inference;
    const at::Tensor embeddings = nec::tat::embed_skeletons(*s->owo->encoder, skeletons, names, nullptr);
    const at::Tensor out = s->model->embed_motion(features, joint_mask, frame_mask, embeddings);
    benchmark::DoNotOptimize(out.data_ptr());
  }
  state.counters["clips_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kBatch), benchmark::Counter::kIsRate);
}

void BM_RetrievalQuery(benchmark::State& state) {
  torch::set_num_threads(static_cast<int>(state.range(0)));
  Setup* s = setup_or_skip(state);
  if (s == nullptr) return;
  nec::evaluator::RetrievalIndex index;
  index.dim = static_cast<int>(s->model->config().motion.output_dim);
  torch::manual_seed(3);
  const at::Tensor rows = torch::nn::functional::normalize(
      torch::randn({kIndexClips, index.dim}), torch::nn::functional::NormalizeFuncOptions().dim(1));
  index.clip_embeddings.assign(rows.data_ptr<float>(), rows.data_ptr<float>() + rows.numel());
  for (int64_t i = 0; i < kIndexClips; ++i) index.clips.push_back(static_cast<int>(i));
  const int64_t captions_per_clip = state.range(1);
  if (captions_per_clip > 0) {
    if (!fs::exists(nec::text::default_sentence_encoder_dir() + "/model.json")) {
      state.SkipWithError("no sentence encoder: run scripts/setup_sentence_encoder.sh");
      return;
    }
    index.text_dim = 512;
    const at::Tensor texts = torch::nn::functional::normalize(torch::randn({kIndexClips * captions_per_clip, index.text_dim}),
                                                              torch::nn::functional::NormalizeFuncOptions().dim(1));
    index.caption_texts.assign(texts.data_ptr<float>(), texts.data_ptr<float>() + texts.numel());
    for (int64_t i = 0; i < kIndexClips; ++i) {
      std::vector<int>& rows = index.clip_captions.emplace_back();
      for (int64_t c = 0; c < captions_per_clip; ++c) rows.push_back(static_cast<int>(i * captions_per_clip + c));
    }
  }
  const std::vector<std::string> all = captions();
  size_t next = 0;
  for (auto _ : state) {
    c10::InferenceMode inference;
    const std::string& caption = all[next++ % all.size()];
    const at::Tensor query = s->model->embed_text(s->reader.read({caption}, &*s->vectors, "query"));
    nec::evaluator::CaptionBlend blend;
    if (captions_per_clip > 0) blend = {nec::evaluator::caption_text_vectors({caption}, "query"), 0.5f};
    const std::vector<nec::evaluator::Match> top = index.nearest_clips(query, 5, {}, blend);
    benchmark::DoNotOptimize(top.data());
  }
}

template <typename Registered>
void common(Registered* b, int64_t iterations) {
  b->Iterations(iterations)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime()
      ->MeasureProcessCPUTime()
      ->ComputeStatistics("min", nec::bench::smallest)
      ->ComputeStatistics("max", nec::bench::largest)
      ->DisplayAggregatesOnly(true);
}

void register_all() {
  for (const int64_t joints : {22, 100}) {
    common(benchmark::RegisterBenchmark("BM_EvaluatorTrainStep", BM_EvaluatorTrainStep)
               ->ArgNames({"joints", "threads"})
               ->Args({joints, 1})
               ->Args({joints, 2}),
           joints == 22 ? kTrainIterations22 : kTrainIterations100);
  }
  common(benchmark::RegisterBenchmark("BM_EncodeCaptions", BM_EncodeCaptions)->ArgNames({"threads"})->Arg(1)->Arg(2), 20);
  common(benchmark::RegisterBenchmark("BM_EncodeSentences", BM_EncodeSentences)->ArgNames({"threads"})->Arg(1)->Arg(2), 20);
  for (const int64_t joints : {22, 100}) {
    common(benchmark::RegisterBenchmark("BM_EmbedMotions", BM_EmbedMotions)
               ->ArgNames({"joints", "threads"})
               ->Args({joints, 1})
               ->Args({joints, 2}),
           joints == 22 ? 5 : 2);
  }
  common(benchmark::RegisterBenchmark("BM_RetrievalQuery", BM_RetrievalQuery)
             ->ArgNames({"threads", "captions"})
             ->ArgsProduct({{1, 2}, {0, 3}}),
         50);
}

}  // namespace

int main(int argc, char** argv) {
  nec::train::keep_large_allocations_in_heap();  // as nec does
  std::vector<char*> args(argv, argv + argc);
  std::string repetitions = "--benchmark_repetitions=" + std::to_string(kDefaultRepetitions);
  bool has_repetitions = false;
  for (char* arg : args) has_repetitions |= std::strncmp(arg, "--benchmark_repetitions", 23) == 0;
  if (!has_repetitions) args.push_back(repetitions.data());
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  for (int i = 1; i < count; ++i) {
    if (!nec::bench::take_step_flag(args[i])) {
      std::fprintf(stderr, "bench_evaluator: unknown argument '%s' (--configs=DIR, --profile_ops=DIR or --benchmark_* flags)\n",
                   args[i]);
      return 2;
    }
  }
  try {
    train_config();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_evaluator: %s\n", e.what());
    return 1;
  }
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
