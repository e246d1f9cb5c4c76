// Text to token codes for one skeleton, segment after segment.
#include "nec/gpt/generation.h"

#include "nec/gpt/token_set.h"
#include "nec/motion/error.h"
#include "nec/motion/random.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>

namespace nec::gpt {

tat::TokenFile GeneratorSession::token_file(const at::Tensor& codes, const std::string& caption) const {
  const tat::TatConfig& config = tokenizer.model.tokenizer->config();
  const at::Tensor values = codes.to(torch::kInt32).contiguous();
  tat::TokenFile tokens;
  tokens.fps = fps();
  tokens.downsampling = static_cast<int>(config.downsampling());
  tokens.frames = static_cast<int>(values.size(0)) * tokens.downsampling;
  tokens.layers = static_cast<int>(config.quantizer.layers);
  tokens.codebook_size = static_cast<int>(config.quantizer.codebook_size);
  tokens.model_kind = tat::to_string(config.kind);
  tokens.training_step = tokenizer.model.info.training_step;
  tokens.source_file = "generated: " + caption;
  tokens.codes.assign(values.data_ptr<int32_t>(), values.data_ptr<int32_t>() + values.numel());
  return tokens;
}

GeneratorSession open_generator(const std::string& dir, const std::string& glove) {
  GeneratorSession session;
  session.gpt = load_gpt_checkpoint(dir);
  session.tokenizer = tat::open_tokenizer_session(session.gpt.tat_dir, glove, -1);
  const int64_t word_dim = session.gpt.model->config().text.word_dim;
  if (word_dim > 0) session.caption_vectors.emplace(text::WordVectors::load_checked(glove, word_dim));
  return session;
}

std::vector<at::Tensor> generate_codes(GeneratorSession& session, const PreparedClip& target,
                                       const std::vector<Segment>& segments, int samples,
                                       const SamplingOptions& options) {
  if (segments.empty() || samples < 1) throw std::invalid_argument("generate_codes: needs a segment and a sample");
  TokenGptImpl& gpt = *session.gpt.model;
  const GptConfig& config = gpt.config();
  c10::InferenceMode inference;
  const text::WordVectors* owo_vectors = session.tokenizer.vectors ? &*session.tokenizer.vectors : nullptr;
  const at::Tensor skeleton =
      skeleton_features(*session.tokenizer.model.owo->encoder, {target.clip.skeleton}, {target.canonical_names},
                        owo_vectors);
  const at::Tensor one_row = torch::zeros({1}, torch::kInt64);
  std::vector<at::Tensor> sequences(static_cast<size_t>(samples),
                                    torch::zeros({0, config.codebook_layers}, torch::kInt64));
  for (size_t s = 0; s < segments.size(); ++s) {
    if (options.on_segment) options.on_segment(s, segments.size());
    const Segment& segment = segments[s];
    const text::TextBatch caption =
        session.gpt.captions.read({segment.caption}, session.caption_vectors ? &*session.caption_vectors : nullptr,
                                  segments.size() > 1 ? "caption " + std::to_string(s + 1) : "the caption");
    const GptCondition condition = gpt.condition(caption, skeleton, {});
    const GptCondition unconditioned = gpt.unconditioned(skeleton);
    SequenceLength length;
    length.steps = segment.steps;
    length.max_steps = config.max_steps - 1;
    SamplingOptions segment_options = options;
    segment_options.seed = s == 0 ? options.seed : mix64(options.seed ^ mix64(s));
    const bool aligned = std::all_of(sequences.begin(), sequences.end(),
                                     [&](const at::Tensor& t) { return t.size(0) == sequences[0].size(0); });
    std::vector<std::vector<int64_t>> groups;  // rows sampled together (same context length)
    if (aligned) {
      groups.emplace_back();
      for (int i = 0; i < samples; ++i) groups.back().push_back(i);
    } else {
      for (int i = 0; i < samples; ++i) groups.push_back({i});
    }
    for (const std::vector<int64_t>& rows : groups) {
      const at::Tensor repeat = one_row.expand({static_cast<int64_t>(rows.size())}).contiguous();
      std::vector<at::Tensor> contexts;
      for (const int64_t row : rows) contexts.push_back(sequences[static_cast<size_t>(row)]);
      const at::Tensor context = torch::stack(contexts);
      SamplingOptions group_options = segment_options;
      group_options.seed = segment_options.seed + static_cast<uint64_t>(rows.front());
      const GptCondition u = unconditioned.select(repeat);
      const std::vector<at::Tensor> drawn =
          sample_codes(gpt, condition.select(repeat), &u, context, length, group_options);
      for (size_t i = 0; i < rows.size(); ++i) {
        at::Tensor& sequence = sequences[static_cast<size_t>(rows[i])];
        sequence = torch::cat({sequence, drawn[i]});
      }
    }
  }
  return sequences;
}

}  // namespace nec::gpt
