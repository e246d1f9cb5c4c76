// Runtime options shared by the commands that run torch models (DESIGN.md, Runtime).
#pragma once

#include "command_line.h"

#include <c10/core/Device.h>

namespace nec::app {

// The --threads option: N > 0, or 0 for every core; UsageError when negative.
int threads_option(const CommandLine& cli);
// torch::set_num_threads(threads), 0 meaning every core.
void use_torch_threads(int threads);
// The --device option: cpu, cuda or cuda:N (train::training_device); UsageError for an unknown name.
c10::Device device_option(const CommandLine& cli);

}  // namespace nec::app
