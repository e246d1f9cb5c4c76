// The synthetic GPT batch and the bare training step shared with the Python peer.
#include "nec/gpt/synthetic.h"

#include "nec/train/optimizer.h"

#include <torch/torch.h>

#include <stdexcept>

namespace nec::gpt {

SyntheticGptBatch synthetic_gpt_batch(const GptConfig& model, int64_t batch_size, double caption_dropout) {
  if (model.text.backbone != text::kUseLiteBackbone) {
    throw std::invalid_argument("synthetic_gpt_batch: draws the use-lite backbone's outputs, the model reads '" +
                                model.text.backbone + "'");
  }
  const int64_t b = batch_size, r = model.codebook_layers, k = model.codebook_size, window = model.max_steps - 1;
  SyntheticGptBatch out;
  // Each item's crop and the step after it; the crop starts at step 0 of these codes.
  const at::Tensor codes = torch::randint(0, k, {b, window + 1, r}, torch::kLong);
  const at::Tensor clip_steps = torch::randint(kSyntheticMinClipSteps, kSyntheticMaxClipSteps + 1, {b}, torch::kLong);
  const at::Tensor lengths = clip_steps.clamp_max(window);
  const at::Tensor starts = (torch::rand({b}) * (clip_steps - lengths + 1).to(torch::kFloat32)).floor().to(torch::kLong);
  const at::Tensor reaches_end = (starts + lengths == clip_steps).view({b, 1, 1});
  const int64_t s = lengths.max().item<int64_t>();
  const at::Tensor step = torch::arange(s + 1, torch::kLong).view({1, s + 1, 1});
  const at::Tensor length = lengths.view({b, 1, 1});
  const at::Tensor crop = codes.narrow(1, 0, s + 1);
  out.batch.inputs = crop.narrow(1, 0, s) * (step.narrow(1, 0, s) < length);
  at::Tensor end_codes = torch::full({r}, -1, torch::kLong);
  end_codes.select(0, 0).fill_(k);
  out.batch.targets = torch::where((step == length).logical_and(reaches_end), end_codes.expand_as(crop),
                                   torch::where(step <= length, crop, torch::full_like(crop, -1)));
  out.batch.drop_text = torch::rand({b}) < caption_dropout;
  out.batch.skeleton_features = torch::randn({b, skeleton_feature_width(model.skeleton_dim)});

  const at::Tensor pieces = torch::randint(kSyntheticMinPieces, kSyntheticMaxPieces + 1, {b}, torch::kLong);
  const int64_t p = pieces.max().item<int64_t>();
  out.captions.mask = torch::arange(p, torch::kLong).view({1, p}) < pieces.view({b, 1});
  out.captions.encoder_features =
      torch::randn({b, p, text::kUseLiteWidth}) * out.captions.mask.unsqueeze(-1).to(torch::kFloat32);
  // Unit rows through elementary ops: Python's normalize takes the norm through another kernel than LibTorch's.
  const at::Tensor sentence = torch::randn({b, text::kUseLiteWidth});
  out.captions.encoder_sentence = sentence * sentence.square().sum(1, true).rsqrt();
  return out;
}

double synthetic_gpt_train_step(TokenGptImpl& model, torch::optim::Optimizer& optimizer,
                                const SyntheticGptBatch& inputs, const GptTrainConfig& config, int64_t step) {
  const double lr = train::LearningRateSchedule(config.optimizer, config.steps).at(step);
  model.train();
  optimizer.zero_grad();
  const GptLoss loss = teacher_forced_loss(model, inputs.captions, inputs.batch, config.token_keep,
                                           inputs.batch.inputs.size(0), model.parameters().front().device());
  loss.loss.backward();
  const double loss_value = loss.loss.item<double>();
  train::optimizer_step(optimizer, model.parameters(), config.optimizer.grad_clip, lr);
  return loss_value;
}

}  // namespace nec::gpt
