// Caption batches built by hand.
#include "text_encoder_support.h"

#include <torch/torch.h>

#include <algorithm>

namespace nec::testing {

text::TextBatch piece_batch(const std::vector<std::vector<int64_t>>& rows) {
  size_t longest = 1;
  for (const auto& row : rows) longest = std::max(longest, row.size());
  const int64_t b = static_cast<int64_t>(rows.size()), p = static_cast<int64_t>(longest);
  text::TextBatch batch;
  batch.ids = torch::zeros({b, p}, torch::kInt64);
  batch.word_vectors = torch::zeros({b, p, 0});
  batch.word_known = torch::zeros({b, p, 1});
  batch.mask = torch::zeros({b, p}, torch::kBool);
  for (int64_t i = 0; i < b; ++i) {
    for (size_t k = 0; k < rows[static_cast<size_t>(i)].size(); ++k) {
      batch.ids[i][static_cast<int64_t>(k)] = rows[static_cast<size_t>(i)][k];
      batch.mask[i][static_cast<int64_t>(k)] = true;
    }
  }
  return batch;
}

}  // namespace nec::testing
