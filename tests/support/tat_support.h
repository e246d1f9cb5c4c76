// Test helpers for the tokenizer's tests (torch): batches built by hand.
#pragma once

#include "nec/motion/motion.h"
#include "nec/owo/pretrain.h"
#include "nec/tat/batch_tensors.h"

#include <vector>

namespace nec::testing {

// Zero-padded batch of the clips' Θ, masks, parents and offsets, as the loader makes it.
tat::BatchTensors make_batch(const std::vector<Skeleton>& skeletons, const std::vector<Motion>& motions);

// A small untrained OwO encoder (no names, width 16, one layer) from seed 3, to freeze in trainers' tests.
owo::OwoPretrainer tiny_frozen_owo();

}  // namespace nec::testing
