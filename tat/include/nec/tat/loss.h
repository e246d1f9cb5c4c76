// Training losses of the tokenizer: feature reconstruction (rot6D, squared, and root
// displacement), the root's vertical velocity, joint positions through differentiable FK, commitment.
//
//   ReconstructionLoss l = reconstruction_loss(out.reconstruction, x, out.commitment_loss, LossWeights{});
//   l.total.backward();
#pragma once

#include "nec/tat/batch_tensors.h"

#include <cstdint>

namespace nec::train {
class ConfigVisitor;
}

namespace nec::tat {

struct LossWeights {
  // The defaults lead with the rotations: with the root's terms at their old weights (1 and 4, positions 1,
  // velocities 0.5) their gradient drowned the rotations' and the joints stood still (docs/tokenizer.md).
  double rotation = 1.0;   // mean squared error on the rot6D channels of real joints and frames
  double root = 0.02;      // L1 on the root's motion in model space (model_space.h): body-frame Δ and yaw rate, scaled
  double position = 0.0;   // L1 on FK world positions, root trajectory included (normalized units)
  double velocity = 0.0;   // L1 on frame-to-frame differences of FK positions
  // L1 on the root's rise per frame (Θ's Δy), scaled as the horizontal path (kRootMotionScale). Without it
  // the NEC tokenizers ignore the height they read and decode one height per skeleton: no jump, sit or
  // lie-down comes back (docs/tokenizer.md, "Vertical motion").
  double vertical = 0.08;
  // The step from which the positions' and velocities' terms count (0: from the first). The pose is learnt
  // first: with those terms from the start the joints stood still; added once the pose is there, they bring the
  // path back and the pose stays (docs/tokenizer.md, "Why: an L1 on the rotations").
  int64_t positions_from_step = 0;

  // The weights of training step `step` (1-based): position and velocity 0 before positions_from_step.
  LossWeights at_step(int64_t step) const;
  // Throws std::invalid_argument naming the first negative weight.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, LossWeights& c);  // train/config_fields.h

struct ReconstructionLoss {
  at::Tensor total;  // weighted sum + commitment, differentiable
  double rotation = 0, root = 0, position = 0, velocity = 0, vertical = 0, commitment = 0;  // unweighted terms
};

// prediction (B, T, J, 9) against target.features, masked by target's joint and frame masks.
ReconstructionLoss reconstruction_loss(const at::Tensor& prediction, const BatchTensors& target,
                                       const at::Tensor& commitment_loss, const LossWeights& weights);

}  // namespace nec::tat
