// Skeleton tree helpers and channel layouts.
#include "nec/motion/skeleton.h"

#include <algorithm>
#include <stdexcept>
#include <unordered_set>

namespace nec {

std::string_view channel_name(Channel channel) {
  static constexpr std::string_view kNames[] = {"Xposition", "Yposition", "Zposition",
                                                "Xrotation", "Yrotation", "Zrotation"};
  return kNames[static_cast<int>(channel)];
}

namespace {
Channel rotation_channel(int axis) { return static_cast<Channel>(3 + axis); }
Channel position_channel(int axis) { return static_cast<Channel>(axis); }
}  // namespace

ChannelLayout ChannelLayout::rotations(EulerOrder order) {
  ChannelLayout layout;
  for (int axis : euler_axes(order)) layout.push(rotation_channel(axis));
  return layout;
}

ChannelLayout ChannelLayout::position_rotations(EulerOrder order) {
  ChannelLayout layout;
  for (int axis = 0; axis < 3; ++axis) layout.push(position_channel(axis));
  for (int axis : euler_axes(order)) layout.push(rotation_channel(axis));
  return layout;
}

bool ChannelLayout::has(Channel channel) const {
  return std::find(channels.begin(), channels.begin() + count, channel) != channels.begin() + count;
}

bool ChannelLayout::has_position() const {
  return std::any_of(channels.begin(), channels.begin() + count, is_position);
}

int ChannelLayout::rotation_count() const {
  return static_cast<int>(
      std::count_if(channels.begin(), channels.begin() + count, [](Channel c) { return !is_position(c); }));
}

EulerOrder ChannelLayout::euler_order() const {
  std::array<int, 3> axes{};
  int n = 0;
  bool seen[3] = {false, false, false};
  for (int i = 0; i < count; ++i) {
    if (is_position(channels[i])) continue;
    const int axis = channel_axis(channels[i]);
    axes[n++] = axis;
    seen[axis] = true;
  }
  if (n == 0) return EulerOrder::ZXY;
  for (int axis = 0; axis < 3; ++axis) {
    if (!seen[axis]) axes[n++] = axis;
  }
  return euler_order_from_axes(axes);
}

ChannelLayout ChannelLayout::with_euler_order(EulerOrder order) const {
  ChannelLayout out;
  const auto axes = euler_axes(order);
  int next_axis = 0;
  for (int i = 0; i < count; ++i) {
    if (is_position(channels[i])) {
      out.push(channels[i]);
      continue;
    }
    // Skip target axes the layout does not carry.
    while (!has(rotation_channel(axes[next_axis]))) ++next_axis;
    out.push(rotation_channel(axes[next_axis++]));
  }
  return out;
}

bool ChannelLayout::operator==(const ChannelLayout& other) const {
  return count == other.count && std::equal(channels.begin(), channels.begin() + count, other.channels.begin());
}

int Skeleton::add_joint(std::string name, int parent, const Vec3& offset, ChannelLayout layout) {
  names.push_back(std::move(name));
  parents.push_back(parent);
  offsets.push_back(offset);
  channels.push_back(layout);
  return joint_count() - 1;
}

void Skeleton::validate() const {
  const int n = joint_count();
  if (n == 0) throw std::invalid_argument("skeleton has no joints");
  if (static_cast<int>(parents.size()) != n || static_cast<int>(offsets.size()) != n ||
      static_cast<int>(channels.size()) != n) {
    throw std::invalid_argument("skeleton arrays have different lengths");
  }
  if (parents[0] != -1) throw std::invalid_argument("joint 0 must be the root (parent -1)");
  std::unordered_set<std::string> seen;
  for (int j = 0; j < n; ++j) {
    if (names[j].empty()) throw std::invalid_argument("joint " + std::to_string(j) + " has an empty name");
    if (!seen.insert(names[j]).second) throw std::invalid_argument("duplicate joint name '" + names[j] + "'");
    if (j > 0 && (parents[j] < 0 || parents[j] >= j)) {
      throw std::invalid_argument("joint '" + names[j] + "' must have a parent listed before it");
    }
    if (!offsets[j].allFinite()) throw std::invalid_argument("joint '" + names[j] + "' has a non-finite offset");
  }
  for (const EndSite& site : end_sites) {
    if (site.parent < 0 || site.parent >= n) throw std::invalid_argument("end site with an invalid parent");
  }
}

int Skeleton::find(std::string_view name) const {
  for (int j = 0; j < joint_count(); ++j) {
    if (names[j] == name) return j;
  }
  return -1;
}

std::vector<int> Skeleton::children(int joint) const {
  std::vector<int> out;
  for (int j = joint + 1; j < joint_count(); ++j) {
    if (parents[j] == joint) out.push_back(j);
  }
  return out;
}

std::vector<std::vector<int>> Skeleton::children_lists() const {
  std::vector<std::vector<int>> out(joint_count());
  for (int j = 1; j < joint_count(); ++j) out[parents[j]].push_back(j);
  return out;
}

int Skeleton::depth(int joint) const {
  int d = 0;
  for (int j = joint; parents[j] >= 0; j = parents[j]) ++d;
  return d;
}

std::vector<int> Skeleton::path_to_root(int joint) const {
  std::vector<int> out;
  for (int j = joint; j >= 0; j = parents[j]) out.push_back(j);
  return out;
}

int Skeleton::lowest_common_ancestor(int a, int b) const {
  // Parents precede children, so the larger index is never an ancestor of the smaller.
  while (a != b) {
    if (a > b) {
      a = parents[a];
    } else {
      b = parents[b];
    }
  }
  return a;
}

std::vector<int> Skeleton::path(int from, int to) const {
  const int lca = lowest_common_ancestor(from, to);
  std::vector<int> up;
  for (int j = from; j != lca; j = parents[j]) up.push_back(j);
  up.push_back(lca);
  std::vector<int> down;
  for (int j = to; j != lca; j = parents[j]) down.push_back(j);
  up.insert(up.end(), down.rbegin(), down.rend());
  return up;
}

std::vector<int> Skeleton::leaves() const {
  std::vector<bool> has_child(joint_count(), false);
  for (int j = 1; j < joint_count(); ++j) has_child[parents[j]] = true;
  std::vector<int> out;
  for (int j = 0; j < joint_count(); ++j) {
    if (!has_child[j]) out.push_back(j);
  }
  return out;
}

std::vector<int> Skeleton::depth_first_order() const {
  const auto children = children_lists();
  std::vector<int> order;
  std::vector<int> stack = {0};
  while (!stack.empty()) {
    const int j = stack.back();
    stack.pop_back();
    order.push_back(j);
    stack.insert(stack.end(), children[j].rbegin(), children[j].rend());
  }
  return order;
}

double Skeleton::diameter() const {
  std::vector<double> reach(joint_count(), 0.0);  // chain length from the root
  double longest = 0.0;
  for (int j = 1; j < joint_count(); ++j) {
    reach[j] = reach[parents[j]] + offsets[j].norm();
    longest = std::max(longest, reach[j]);
  }
  for (const EndSite& site : end_sites) longest = std::max(longest, reach[site.parent] + site.offset.norm());
  return longest;
}

std::vector<double> Skeleton::bone_lengths() const {
  std::vector<double> out(joint_count(), 0.0);
  for (int j = 1; j < joint_count(); ++j) out[j] = offsets[j].norm();
  return out;
}

}  // namespace nec
