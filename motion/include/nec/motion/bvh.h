// BVH reading and writing.
//
//   Clip clip = read_bvh("walk.bvh");                 // throws InputError
//   write_bvh("out.bvh", clip.skeleton, clip.motion);  // atomic
//
// The reader takes what real files contain: 0–6 channels per joint in any
// order, position channels on any joint, End Site, CRLF, tabs, blank lines,
// scientific notation and joint names with spaces. It rejects, before
// allocating, frame counts the file is too small to hold, and names the line
// of every problem. The writer keeps names, channel layout and Euler order.
#pragma once

#include "nec/motion/motion.h"

#include <optional>
#include <string>
#include <string_view>

namespace nec {

struct BvhLimits {
  int max_joints = 4096;          // more joints than this is rejected
  double min_frame_time = 1e-5;   // seconds; 100 kHz
  double max_frame_time = 10.0;   // seconds
};

// `name` is used in error messages (usually the path).
Clip parse_bvh(std::string_view text, const std::string& name, const BvhLimits& limits = {});
Clip read_bvh(const std::string& path, const BvhLimits& limits = {});

struct BvhWriteOptions {
  std::optional<EulerOrder> euler_order;  // rewrite every joint's rotations in this order
};

std::string format_bvh(const Skeleton& skeleton, const Motion& motion, const BvhWriteOptions& options = {});
void write_bvh(const std::string& path, const Skeleton& skeleton, const Motion& motion,
               const BvhWriteOptions& options = {});

}  // namespace nec
