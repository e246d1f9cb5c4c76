// The input check every metric of metrics.h makes (private to evaluator/metrics/).
#pragma once

#include "nec/evaluator/metrics.h"

#include <stdexcept>
#include <string>

namespace nec::evaluator {

// Throws std::invalid_argument naming `what` when `embeddings` has fewer than
// `min_rows` rows, no column, or a value that is not finite.
inline void require_embeddings(const Embeddings& embeddings, const std::string& what, int min_rows) {
  if (embeddings.rows() < min_rows || embeddings.cols() < 1) {
    throw std::invalid_argument(what + ": needs at least " + std::to_string(min_rows) + " rows and 1 column, has " +
                                std::to_string(embeddings.rows()) + " x " + std::to_string(embeddings.cols()));
  }
  if (!embeddings.allFinite()) throw std::invalid_argument(what + ": has a non-finite value");
}

}  // namespace nec::evaluator
