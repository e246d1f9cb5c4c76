// Test helpers of the models that read captions through the text encoder (torch).
#pragma once

#include "nec/text/text_encoder.h"

#include <cstdint>
#include <vector>

namespace nec::testing {

// Captions given as piece ids (>= 2: 0 pads, 1 is unknown), without word vectors, padded to the longest.
text::TextBatch piece_batch(const std::vector<std::vector<int64_t>>& rows);

}  // namespace nec::testing
