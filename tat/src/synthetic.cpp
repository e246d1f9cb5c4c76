// Synthetic inputs and the bare training step shared with the Python peer.
#include "nec/tat/synthetic.h"

#include "nec/tat/fk.h"
#include "nec/tat/loss.h"
#include "nec/train/optimizer.h"

#include <torch/torch.h>

#include <vector>

namespace nec::tat {

at::Tensor random_rot6d(at::IntArrayRef leading) {
  std::vector<int64_t> shape(leading.begin(), leading.end());
  shape.push_back(6);
  return matrix_to_rot6d(rot6d_to_matrix(torch::randn(shape)));
}

at::Tensor random_features(int64_t batch, int64_t frames, int64_t joints) {
  const at::Tensor rotations = random_rot6d({batch, frames, joints});
  at::Tensor root_delta = torch::randn({batch, frames, 3}) * 0.02;
  root_delta.select(1, 0).zero_();
  root_delta.select(1, 0).select(1, 1).fill_(0.9);
  at::Tensor translation = torch::zeros({batch, frames, joints, 3});
  translation.select(2, 0).copy_(root_delta);
  return torch::cat({translation, rotations}, -1);
}

SyntheticBatch synthetic_batch(int64_t batch, int64_t frames, int64_t joints, int64_t embedding_dim) {
  SyntheticBatch out;
  out.batch.features = random_features(batch, frames, joints);
  // parent(j) uniform in [0, j - 1]: a random tree with parents before children; -1 for the root.
  const at::Tensor index = torch::arange(joints, torch::kLong);
  out.batch.parents =
      torch::minimum((torch::rand({batch, joints}) * index.to(torch::kFloat)).floor().to(torch::kLong), index - 1);
  out.batch.offsets = torch::randn({batch, joints, 3}) * 0.1;
  out.batch.offsets.select(1, 0).zero_();
  out.batch.joint_mask = torch::ones({batch, joints}, torch::kBool);
  out.batch.frame_mask = torch::ones({batch, frames}, torch::kBool);
  out.embeddings = torch::randn({batch, joints, embedding_dim});
  return out;
}

double synthetic_train_step(TokenizerImpl& model, torch::optim::Optimizer& optimizer, const SyntheticBatch& inputs,
                            const TatTrainConfig& config, int64_t step) {
  const double lr = train::LearningRateSchedule(config.optimizer, config.steps).at(step);
  model.train();
  const BatchTensors& x = inputs.batch;
  const TokenizerOutput out = model.forward(x.features, x.joint_mask, x.frame_mask, inputs.embeddings);
  const ReconstructionLoss loss =
      reconstruction_loss(out.reconstruction, x, out.commitment_loss, config.loss.at_step(step));
  optimizer.zero_grad();
  loss.total.backward();
  train::optimizer_step(optimizer, model.parameters(), config.optimizer.grad_clip, lr);
  model.update_codebooks();
  return loss.total.item<double>();
}

}  // namespace nec::tat
