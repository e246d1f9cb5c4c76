// The process's allocator settings for torch work.
#pragma once

namespace nec::train {

// Keeps large blocks in glibc's heap: tensors of several MB are allocated and freed every step, and by
// default glibc maps and unmaps each one, so every step page-faults its working set again (it made diffusion
// sampling 4-5x slower). Call once at the start of a program that runs torch models.
void keep_large_allocations_in_heap();

}  // namespace nec::train
