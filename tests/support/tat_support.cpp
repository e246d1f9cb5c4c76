// Test helpers for the tokenizer's tests (torch).
#include "tat_support.h"

#include "nec/motion/features.h"

#include <torch/torch.h>

#include <algorithm>

namespace nec::testing {

// Zero-padded batch of the clips' Θ, masks, parents and offsets, as the loader makes it.
tat::BatchTensors make_batch(const std::vector<Skeleton>& skeletons, const std::vector<Motion>& motions) {
  const int64_t b = static_cast<int64_t>(skeletons.size());
  int64_t t = 0, j = 0;
  for (size_t i = 0; i < skeletons.size(); ++i) {
    t = std::max<int64_t>(t, motions[i].frame_count);
    j = std::max<int64_t>(j, skeletons[i].joint_count());
  }
  tat::BatchTensors x;
  x.features = torch::zeros({b, t, j, 9});
  x.joint_mask = torch::zeros({b, j}, torch::kBool);
  x.frame_mask = torch::zeros({b, t}, torch::kBool);
  x.parents = torch::full({b, j}, -1, torch::kLong);
  x.offsets = torch::zeros({b, j, 3});
  for (int64_t i = 0; i < b; ++i) {
    const Skeleton& s = skeletons[i];
    const Features f = encode_features(s, motions[i]);
    const int64_t joints = s.joint_count(), frames = f.frame_count;
    x.features[i].narrow(0, 0, frames).narrow(1, 0, joints).copy_(
        torch::from_blob(const_cast<float*>(f.data.data()), {frames, joints, 9}, torch::kFloat32));
    x.joint_mask[i].narrow(0, 0, joints).fill_(true);
    x.frame_mask[i].narrow(0, 0, frames).fill_(true);
    for (int64_t k = 0; k < joints; ++k) {
      x.parents[i][k] = s.parents[k];
      for (int c = 0; c < 3; ++c) x.offsets[i][k][c] = s.offsets[k][c];
    }
  }
  return x;
}

owo::OwoPretrainer tiny_frozen_owo() {
  torch::manual_seed(3);
  owo::OwoConfig encoder;
  encoder.name_dim = 0;
  encoder.dim = 16;
  encoder.layers = 1;
  encoder.heads = 2;
  encoder.edge_dim = 8;
  return owo::OwoPretrainer(encoder, owo::PretrainConfig{});
}

}  // namespace nec::testing
