// Device names: cpu, cuda, cuda:N.
#include "nec/train/device.h"

#include <torch/torch.h>

#include <stdexcept>

namespace nec::train {

c10::Device training_device(const std::string& name) {
  if (name == "cpu") return c10::Device(c10::kCPU);
  if (name.rfind("cuda", 0) != 0) {
    throw std::invalid_argument("unknown device '" + name + "' (known: cpu, cuda, cuda:N)");
  }
  c10::Device device(c10::kCPU);
  try {
    device = c10::Device(name);
  } catch (const c10::Error&) {
    throw std::invalid_argument("unknown device '" + name + "' (known: cpu, cuda, cuda:N)");
  }
  if (!torch::cuda::is_available()) {
    throw std::runtime_error("--device " + name + ": this nec's torch has no CUDA device (" +
                             "a CPU-only libtorch, or no GPU visible); use --device cpu");
  }
  if (device.has_index() && device.index() >= static_cast<int>(torch::cuda::device_count())) {
    throw std::runtime_error("--device " + name + ": only " + std::to_string(torch::cuda::device_count()) +
                             " CUDA device(s) visible");
  }
  return device;
}

}  // namespace nec::train
