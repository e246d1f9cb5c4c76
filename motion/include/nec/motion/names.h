// Canonical joint names (DESIGN.md, preprocessing step 4).
//
//   canonical_joint_name("LeftUpLeg")       == "left upper leg"
//   canonical_joint_name("Bip01 R Thigh")   == "right upper leg"
//   canonical_joint_name("thigh.L")         == "left upper leg"
//   canonical_joint_name("joint12")         == "joint"
//
// Splits CamelCase, '_', '.', '-', spaces and digits; turns side markers
// (L, R, Left, l_, .L, ...) into "left"/"right" at the front; maps synonyms
// (thigh -> upper leg, ...); drops rig prefixes (Bip01, mixamorig, joint_).
// The original names stay in the Skeleton: BVH output always uses them.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace nec {

enum class Side { None, Left, Right };

std::string canonical_joint_name(std::string_view name);
// The lower-case words of a name after splitting, before synonym mapping.
std::vector<std::string> split_joint_name(std::string_view name);
Side joint_side(std::string_view name);
// The canonical name with its side word swapped ("left hand" -> "right hand").
std::string mirrored_canonical_name(const std::string& canonical);

}  // namespace nec
