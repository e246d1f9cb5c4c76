// Skeleton: the joint tree of a rig, with rest offsets, end sites and the
// per-joint BVH channel layout it was read with.
//
//   Skeleton s = read_bvh("dog.bvh").skeleton;
//   for (int c : s.children(0)) ...;   int d = s.depth(j);   double h = s.diameter();
//
// Invariants (checked by validate()): parents come before children, joint 0
// is the only root (parent -1), names are unique and non-empty.
#pragma once

#include "nec/motion/rotations.h"

#include <array>
#include <string>
#include <vector>

namespace nec {

enum class Channel : unsigned char { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };

std::string_view channel_name(Channel channel);
inline bool is_position(Channel channel) { return static_cast<int>(channel) < 3; }
inline int channel_axis(Channel channel) { return static_cast<int>(channel) % 3; }  // 0 = X, 1 = Y, 2 = Z

// The channels of one joint in file order (0 to 6 channels, each at most once).
struct ChannelLayout {
  std::array<Channel, 6> channels{};
  int count = 0;

  static ChannelLayout rotations(EulerOrder order);            // 3 rotation channels
  static ChannelLayout position_rotations(EulerOrder order);   // XYZ position + 3 rotations
  void push(Channel channel) { channels[count++] = channel; }
  bool has(Channel channel) const;
  bool has_position() const;
  int rotation_count() const;
  // Euler order of the rotation channels; axes missing from the layout follow
  // in X, Y, Z order (ZXY when the layout has no rotation channel).
  EulerOrder euler_order() const;
  // The same layout with its rotation channels reordered to `order`.
  ChannelLayout with_euler_order(EulerOrder order) const;
  bool operator==(const ChannelLayout& other) const;
};

struct EndSite {
  int parent = 0;  // joint the end site hangs from
  Vec3 offset = Vec3::Zero();
};

struct Skeleton {
  std::vector<std::string> names;          // (J) as in the source file
  std::vector<int> parents;                // (J) parent index, -1 for the root
  std::vector<Vec3> offsets;               // (J) rest offset from the parent, in the parent's frame
  std::vector<ChannelLayout> channels;     // (J) BVH channel layout
  std::vector<EndSite> end_sites;          // leaf markers (BVH "End Site")

  int joint_count() const { return static_cast<int>(names.size()); }
  // Appends a joint; returns its index.
  int add_joint(std::string name, int parent, const Vec3& offset, ChannelLayout layout);
  // Throws std::invalid_argument naming the first broken invariant.
  void validate() const;
  // Index of the joint called `name`, or -1.
  int find(std::string_view name) const;

  std::vector<int> children(int joint) const;
  std::vector<std::vector<int>> children_lists() const;  // (J) children of every joint
  int depth(int joint) const;                             // root has depth 0
  std::vector<int> path_to_root(int joint) const;         // joint, parent, ..., 0
  int lowest_common_ancestor(int a, int b) const;
  std::vector<int> path(int from, int to) const;          // joints from `from` to `to`, through their LCA
  std::vector<int> leaves() const;                        // joints without children
  // Joints in depth-first pre-order, children by index: the order BVH files list them.
  std::vector<int> depth_first_order() const;
  // Length of the longest root-to-leaf chain of offsets, counting end sites.
  double diameter() const;
  std::vector<double> bone_lengths() const;  // (J) |offset|; 0 for the root
};

}  // namespace nec
