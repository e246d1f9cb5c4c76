// Test helpers for the tokenizer's tests (torch): batches built by hand.
#pragma once

#include "nec/motion/motion.h"
#include "nec/tat/batch_tensors.h"

#include <vector>

namespace nec::testing {

// Zero-padded batch of the clips' Θ, masks, parents and offsets, as the loader makes it.
tat::BatchTensors make_batch(const std::vector<Skeleton>& skeletons, const std::vector<Motion>& motions);

}  // namespace nec::testing
