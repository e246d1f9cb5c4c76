// Synthetic evaluator inputs and the bare training step shared with the Python peer.
#include "nec/evaluator/synthetic.h"

#include "nec/tat/synthetic.h"
#include "nec/train/optimizer.h"

#include <torch/torch.h>

namespace nec::evaluator {
namespace {

// (B) counts -> (B, size) bool, true for the first count[i] positions of row i.
at::Tensor leading_mask(const at::Tensor& counts, int64_t size) {
  return torch::arange(size, torch::kLong).unsqueeze(0) < counts.unsqueeze(1);
}

// x (B, N, C) zero where mask (B, N) is false.
at::Tensor masked(const at::Tensor& x, const at::Tensor& mask) { return x * mask.unsqueeze(-1).to(x.scalar_type()); }

}  // namespace

ContrastiveBatch synthetic_contrastive_batch(int64_t batch, int64_t frames, int64_t joints, int64_t embedding_dim) {
  ContrastiveBatch out;
  at::Tensor joint_counts = torch::randint(joints - joints / 4, joints + 1, {batch}, torch::kLong);
  joint_counts[0].fill_(joints);  // the bucket's widest skeleton sets J
  out.joint_mask = leading_mask(joint_counts, joints);
  out.frame_mask = leading_mask(torch::randint(frames / 2, frames + 1, {batch}, torch::kLong), frames);
  const at::Tensor real = out.frame_mask.unsqueeze(2).logical_and(out.joint_mask.unsqueeze(1));  // (B, T, J)
  out.features = tat::random_features(batch, frames, joints) * real.unsqueeze(-1).to(torch::kFloat);
  out.joint_embeddings = masked(torch::randn({batch, joints, embedding_dim}), out.joint_mask);
  out.captions.mask =
      leading_mask(torch::randint(kSyntheticMinPieces, kSyntheticPieces + 1, {batch}, torch::kLong), kSyntheticPieces);
  out.captions.encoder_features = masked(torch::randn({batch, kSyntheticPieces, text::kUseLiteWidth}), out.captions.mask);
  out.captions.encoder_sentence = torch::nn::functional::normalize(
      torch::randn({batch, text::kUseLiteWidth}), torch::nn::functional::NormalizeFuncOptions().dim(1));
  const at::Tensor caption_ids = torch::randint(0, 4 * batch, {batch}, torch::kLong);
  out.same = caption_ids.unsqueeze(1) == caption_ids.unsqueeze(0);
  return out;
}

double synthetic_evaluator_train_step(EvaluatorImpl& model, torch::optim::Optimizer& optimizer,
                                      const ContrastiveBatch& inputs, const EvaluatorTrainConfig& config, int64_t step) {
  const double lr = train::LearningRateSchedule(config.optimizer, config.steps).at(step);
  model.train();
  optimizer.zero_grad();
  const at::Tensor loss = contrastive_batch_loss(model, inputs);
  loss.backward();
  train::optimizer_step(optimizer, model.parameters(), config.optimizer.grad_clip, lr);
  return loss.item<double>();
}

}  // namespace nec::evaluator
