// The skeleton record of skeletons.bin (docs/dataset-format.md), which also
// keys a rig by its hash when the cache is built: internal to corpus/.
#pragma once

#include "nec/motion/skeleton.h"

#include <cstdint>
#include <string>
#include <vector>

namespace nec::detail {

// 16 lower-case hexadecimal digits.
std::string hex16(uint64_t value);

// One skeleton record: joints with names, canonical names, parents, offsets, channels; end sites.
std::string serialize_skeleton(const Skeleton& s, const std::vector<std::string>& canonical_names);

}  // namespace nec::detail
