// Runtime options shared by the torch commands.
#include "torch_runtime.h"

#include "nec/train/device.h"

#include <torch/torch.h>

#include <algorithm>
#include <stdexcept>
#include <thread>

namespace nec::app {

int threads_option(const CommandLine& cli) {
  const int threads = cli.integer("--threads");
  if (threads < 0) throw UsageError("--threads must be >= 0");
  return threads;
}

void use_torch_threads(int threads) {
  torch::set_num_threads(threads > 0 ? threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
}

c10::Device device_option(const CommandLine& cli) {
  try {
    return train::training_device(cli.value("--device"));
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
}

}  // namespace nec::app
