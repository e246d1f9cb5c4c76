// Masked reconstruction loss of the tokenizer: rot6D (squared error), root displacement, the root's vertical
// velocity, FK positions and velocities, plus the quantizer's commitment loss.
#include "nec/tat/loss.h"

#include "nec/tat/fk.h"
#include "nec/tat/model_space.h"
#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <optional>
#include <stdexcept>
#include <string>

namespace nec::tat {
namespace {

void require_weight(double value, const char* name) {
  if (!(value >= 0.0)) throw std::invalid_argument(std::string("LossWeights: ") + name + " must be >= 0, got " +
                                                   std::to_string(value));
}

// Mean of an error (..., C) over the entries where weight (its leading dimensions) is 1: sum / (count * C).
at::Tensor masked_mean(const at::Tensor& error, const at::Tensor& weight) {
  const at::Tensor count = weight.sum() * static_cast<double>(error.size(-1));
  return (error * weight.unsqueeze(-1)).sum() / count.clamp_min(1.0);
}

at::Tensor masked_l1(const at::Tensor& a, const at::Tensor& b, const at::Tensor& weight) {
  return masked_mean((a - b).abs(), weight);
}

}  // namespace

void visit_fields(train::ConfigVisitor& v, LossWeights& c) {
  v.field("rotation", c.rotation, "weight of the squared error on the joints' rotations (rot6D)");
  v.field("root", c.root, "weight of the L1 on the root's motion");
  v.field("position", c.position, "weight of the L1 on world joint positions");
  v.field("velocity", c.velocity, "weight of the L1 on joint velocities");
  v.field("vertical", c.vertical, "weight of the L1 on the root's vertical velocity");
  v.added_field("positions_from_step", c.positions_from_step,
                "step from which the position and velocity terms count (0 = from the first); the rotations lead before");
}

LossWeights LossWeights::at_step(int64_t step) const {
  LossWeights weights = *this;
  if (step < positions_from_step) weights.position = weights.velocity = 0.0;
  return weights;
}

void LossWeights::validate() const {
  require_weight(rotation, "rotation");
  require_weight(root, "root");
  require_weight(position, "position");
  require_weight(velocity, "velocity");
  require_weight(vertical, "vertical");
  if (positions_from_step < 0) {
    throw std::invalid_argument("LossWeights: positions_from_step must be >= 0, got " +
                                std::to_string(positions_from_step));
  }
}

ReconstructionLoss reconstruction_loss(const at::Tensor& prediction, const BatchTensors& target,
                                       const at::Tensor& commitment_loss, const LossWeights& weights) {
  weights.validate();
  if (!prediction.defined() || !prediction.sizes().equals(target.features.sizes())) {
    throw std::invalid_argument("reconstruction_loss: prediction and target features differ in shape");
  }
  const int64_t b = prediction.size(0), t = prediction.size(1), j = prediction.size(2);
  const auto type = prediction.scalar_type();
  const at::Tensor frame = target.frame_mask.to(type);                                     // (B, T)
  const at::Tensor real = frame.view({b, t, 1}) * target.joint_mask.to(type).view({b, 1, j});  // (B, T, J)

  // Squared: under an L1 every joint's error pulls with the same force however small, and the tokenizers learnt
  // each joint's median pose, a still body (docs/tokenizer.md, "Why: an L1 on the rotations").
  const at::Tensor rotation =
      masked_mean((prediction.narrow(-1, 3, 6) - target.features.narrow(-1, 3, 6)).square(), real);
  // The root's motion as the networks predict it (model space: body-frame Δ and yaw rate, scaled).
  const auto root_motion = [](const at::Tensor& features) {
    const at::Tensor root = features_to_model_space(features.narrow(2, 0, 1)).select(2, 0);  // (B, T, 10)
    return torch::cat({root.narrow(-1, 0, 3), root.narrow(-1, 9, 1)}, -1);
  };
  const at::Tensor root = masked_l1(root_motion(prediction), root_motion(target.features), frame);
  // Θ's Δy of frames 1.. is the root's rise per frame (frame 0 holds the height).
  at::Tensor vertical = torch::zeros({}, prediction.options());
  if (t > 1) {
    const auto rise = [t](const at::Tensor& features) {
      return features.select(2, 0).narrow(-1, 1, 1).narrow(1, 1, t - 1) * kRootMotionScale;  // (B, T - 1, 1)
    };
    vertical = masked_l1(rise(prediction), rise(target.features), frame.narrow(1, 1, t - 1) * frame.narrow(1, 0, t - 1));
  }

  // Before positions_from_step the positions' terms weigh 0: they are still logged, but FK's backward is skipped.
  const bool positions_count = weights.position > 0.0 || weights.velocity > 0.0;
  at::Tensor target_positions;
  {
    torch::NoGradGuard no_grad;
    target_positions = features_to_positions(target.features, target.parents, target.offsets).positions;
  }
  std::optional<torch::NoGradGuard> logged_only;
  if (!positions_count) logged_only.emplace();
  const at::Tensor predicted_positions = features_to_positions(prediction, target.parents, target.offsets).positions;
  logged_only.reset();
  const at::Tensor position = masked_l1(predicted_positions, target_positions, real);
  at::Tensor velocity = torch::zeros({}, prediction.options());
  if (t > 1) {
    const auto later = torch::indexing::Slice(1, torch::indexing::None);
    const auto earlier = torch::indexing::Slice(torch::indexing::None, -1);
    const at::Tensor both = real.index({torch::indexing::Slice(), later}) * real.index({torch::indexing::Slice(), earlier});
    velocity = masked_l1(predicted_positions.index({torch::indexing::Slice(), later}) -
                             predicted_positions.index({torch::indexing::Slice(), earlier}),
                         target_positions.index({torch::indexing::Slice(), later}) -
                             target_positions.index({torch::indexing::Slice(), earlier}),
                         both);
  }
  const at::Tensor commitment =
      commitment_loss.defined() ? commitment_loss.to(type).reshape({}) : torch::zeros({}, prediction.options());

  ReconstructionLoss out;
  out.total = weights.rotation * rotation + weights.root * root + weights.position * position +
              weights.velocity * velocity + weights.vertical * vertical + commitment;
  // All six terms in one copy to the CPU (one device sync).
  const at::Tensor terms = torch::stack({rotation, root, position, velocity, vertical, commitment}).detach().to(
      torch::kCPU, torch::kDouble);
  const double* values = terms.data_ptr<double>();
  out.rotation = values[0];
  out.root = values[1];
  out.position = values[2];
  out.velocity = values[3];
  out.vertical = values[4];
  out.commitment = values[5];
  return out;
}

}  // namespace nec::tat
