// The device a model trains or runs on, from its command-line name.
#pragma once

#include <c10/core/Device.h>

#include <string>

namespace nec::train {

// "cpu", "cuda" or "cuda:N" as a device. Throws std::invalid_argument for
// another name, std::runtime_error when this torch has no CUDA device.
c10::Device training_device(const std::string& name);

}  // namespace nec::train
