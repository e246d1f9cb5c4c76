#include "nec/train/heap.h"

#include <malloc.h>

namespace nec::train {

void keep_large_allocations_in_heap() {
  constexpr int kLargeBlock = 1 << 30;  // bytes: no model tensor is mapped on its own, and the heap is never trimmed
  mallopt(M_MMAP_THRESHOLD, kLargeBlock);
  mallopt(M_TRIM_THRESHOLD, kLargeBlock);
}

}  // namespace nec::train
