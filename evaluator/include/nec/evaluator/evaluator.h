// The text-motion evaluator: a motion encoder for any skeleton and the text
// encoder, trained contrastively so that a motion and its caption land close
// (NECromancer section 5; Guo et al. 2022). Its embeddings are what
// retrieval and every generation metric read.
//
//   EvaluatorSession session = open_evaluator("runs/eval/best", /*glove=*/"");
//   at::Tensor texts = session.embed_captions({"a dog trots forward"}, "query");  // (1, D), unit length
//   at::Tensor motions = session.embed_clips(cache, {0, 1, 2});                   // (3, D), unit length
//   at::Tensor scores = texts.matmul(motions.t());                                // cosine similarities
//
// A checkpoint directory holds config.json (format "nec-evaluator"), the
// tensors, the piece model the text encoder reads (backbone "pieces"), and the frozen OwO encoder
// in owo/; a training checkpoint adds the training state and, in best/, the
// evaluator with the best validation R-Precision so far.
#pragma once

#include "nec/evaluator/metrics.h"
#include "nec/evaluator/motion_encoder.h"
#include "nec/corpus/dataset.h"
#include "nec/corpus/preprocess.h"
#include "nec/owo/pretrain.h"
#include "nec/text/text_encoder.h"
#include "nec/text/word_vectors.h"

#include <ATen/core/Tensor.h>
#include <c10/core/Device.h>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace nec::train {
class ConfigVisitor;
}

namespace nec::evaluator {

constexpr const char* kEvaluatorCheckpointFormat = "nec-evaluator";
constexpr int kEvaluatorCheckpointVersion = 2;  // 2: clips in the canonical rest pose (corpus/rest_pose.h)
constexpr const char* kBestCheckpointDir = "best";  // inside a training checkpoint

// Hyper-parameters of the two encoders; saved with a model.
struct EvaluatorConfig {
  MotionEncoderConfig motion;
  text::TextEncoderConfig text;
  double initial_temperature = 0.07;  // of the contrastive softmax; learnt from there (CLIP)

  // Throws std::invalid_argument naming the bad field (also when the two output widths differ).
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, EvaluatorConfig& c);

class EvaluatorImpl : public torch::nn::Module {
 public:
  explicit EvaluatorImpl(const EvaluatorConfig& config);
  const EvaluatorConfig& config() const { return config_; }

  // (B, D) unit-length embeddings. See MotionEncoder::forward for the arguments.
  at::Tensor embed_motion(const at::Tensor& features, const at::Tensor& joint_mask, const at::Tensor& frame_mask,
                          const at::Tensor& joint_embeddings);
  at::Tensor embed_text(const text::TextBatch& batch);
  // exp(learnt log scale), clamped to at most 100: the contrastive logits are scale x cosine.
  at::Tensor logit_scale() const;

  MotionEncoder motion{nullptr};
  text::TextEncoder text{nullptr};

 private:
  EvaluatorConfig config_;
  at::Tensor log_scale_;  // () log(1 / temperature)
};
TORCH_MODULE(Evaluator);

struct EvaluatorCheckpointInfo {
  int64_t training_step = 0;
  std::string data;              // what it was trained on
  double fps = 30.0;             // the corpus fps the motion encoder read
  int64_t window_frames = 64;    // the training crop
  int64_t best_step = 0;         // step of the best validation so far (0: none)
  double best_r_precision = 0;   // its validation R@3
};

// Writes `dir` atomically: config, tensors, what the captions need
// (save_checkpoint_captions) and the OwO checkpoint; `extra` may add files to
// the temporary directory first.
void save_evaluator_checkpoint(const std::string& dir, EvaluatorImpl& model, owo::OwoPretrainerImpl& owo,
                               const text::CaptionReader& captions, const EvaluatorCheckpointInfo& info,
                               const std::function<void(const std::string&)>& extra = {});

struct LoadedEvaluator {
  Evaluator model{nullptr};  // eval mode
  owo::OwoPretrainer owo{nullptr};
  text::CaptionReader captions;
  EvaluatorCheckpointInfo info;
};

// Throws InputError naming the file for a missing or damaged checkpoint, or
// one of another kind or version, with a hint what to run.
LoadedEvaluator load_evaluator_checkpoint(const std::string& dir);

// What EvaluatorSession runs, on any model (e.g. one being trained; put it in
// eval mode first): (N, D) unit-length embeddings of captions, and of clips
// of `cache`, each whole or its middle max_frames when longer.
at::Tensor embed_captions(EvaluatorImpl& model, const text::CaptionReader& reader, const text::WordVectors* vectors,
                          const std::vector<std::string>& captions, const std::string& where, const c10::Device& device);
at::Tensor embed_clips(EvaluatorImpl& model, owo::OwoEncoderImpl& owo, const text::WordVectors* vectors,
                       const DatasetCache& cache, const std::vector<int>& clips, const c10::Device& device);

// One motion to embed: Θ (as batches hold it, facing its start heading) on a normalized skeleton.
struct MotionInput {
  Features features;
  const Skeleton* skeleton = nullptr;
  const std::vector<std::string>* canonical_names = nullptr;
};
// (count, D) embeddings of item(0), ..., item(count - 1), made and embedded a batch at a time.
at::Tensor embed_motions(EvaluatorImpl& model, owo::OwoEncoderImpl& owo, const text::WordVectors* vectors, size_t count,
                         const std::function<MotionInput(size_t)>& item, const c10::Device& device);

// (N, D) float tensor -> the metrics' row matrix (metrics.h).
Embeddings to_embeddings(const at::Tensor& embeddings);

// A loaded evaluator with the word vectors it reads, on a device.
class EvaluatorSession {
 public:
  EvaluatorSession(LoadedEvaluator loaded, std::optional<text::WordVectors> vectors, const c10::Device& device);

  const LoadedEvaluator& loaded() const { return loaded_; }
  int64_t dim() const { return loaded_.model->config().motion.output_dim; }

  // (N, D) unit-length embeddings of the captions (normalized, checked; InputError naming `where`).
  at::Tensor embed_captions(const std::vector<std::string>& captions, const std::string& where);
  // (N, D) of the clips of `cache`: each whole, or its middle max_frames when longer.
  at::Tensor embed_clips(const DatasetCache& cache, const std::vector<int>& clips);
  // (1, D) of a clip prepared for the model (prepare_for_model): whole, or its middle max_frames.
  at::Tensor embed_clip(const PreparedClip& prepared);
  // (N, D) of motions given as Θ on their skeletons (at most max_frames each).
  at::Tensor embed_motion_inputs(const std::vector<MotionInput>& inputs);
  // (N, D) of frame windows [start, start + frames) of a prepared clip.
  at::Tensor embed_clip_windows(const PreparedClip& prepared, const std::vector<int>& starts, int frames);
  // (N, D) of frame windows [start, start + frames) of one clip (Coverage, Novelty).
  at::Tensor embed_windows(const DatasetCache& cache, int clip, const std::vector<int>& starts, int frames);
  // (J, E) OwO joint embeddings of a normalized skeleton.
  at::Tensor joint_embeddings(const Skeleton& skeleton, const std::vector<std::string>& canonical_names);

 private:
  LoadedEvaluator loaded_;
  std::optional<text::WordVectors> vectors_;
  c10::Device device_;
};

// open: load_evaluator_checkpoint + the word vectors the checkpoint reads
// (`glove`, or the default file when empty), on the CPU.
EvaluatorSession open_evaluator(const std::string& dir, const std::string& glove);

}  // namespace nec::evaluator
