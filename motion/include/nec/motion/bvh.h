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
  int max_depth = 1024;           // deepest joint nesting (root = 0); bounds the reader's and writer's recursion
  double max_joint_frames_per_byte = 16.0;  // joint-frames one byte of motion text may describe (real files: ~0.05)
  double min_frame_time = 1e-5;   // seconds; 100 kHz
  double max_frame_time = 10.0;   // seconds
};

// `name` is used in error messages (usually the path).
Clip parse_bvh(std::string_view text, const std::string& name, const BvhLimits& limits = {});
Clip read_bvh(const std::string& path, const BvhLimits& limits = {});

struct BvhWriteOptions {
  std::optional<EulerOrder> euler_order;  // rewrite the rotations of every joint with 3 rotation channels in this order
};

std::string format_bvh(const Skeleton& skeleton, const Motion& motion, const BvhWriteOptions& options = {});
void write_bvh(const std::string& path, const Skeleton& skeleton, const Motion& motion,
               const BvhWriteOptions& options = {});

}  // namespace nec
