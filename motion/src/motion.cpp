// Motion construction and slicing.
#include "nec/motion/motion.h"

#include <stdexcept>

namespace nec {

Motion Motion::rest(const Skeleton& skeleton, int frames, double fps) {
  Motion m;
  m.fps = fps;
  m.frame_count = frames;
  m.joint_count = skeleton.joint_count();
  m.rotations.assign(static_cast<size_t>(frames) * m.joint_count, Quat::Identity());
  m.translations.resize(m.rotations.size());
  for (int t = 0; t < frames; ++t) {
    for (int j = 0; j < m.joint_count; ++j) m.translation(t, j) = skeleton.offsets[j];
  }
  return m;
}

Motion Motion::slice(int begin, int end) const {
  if (begin < 0 || end > frame_count || begin >= end) {
    throw std::out_of_range("Motion::slice: bad frame range");
  }
  Motion out;
  out.fps = fps;
  out.frame_count = end - begin;
  out.joint_count = joint_count;
  const size_t first = static_cast<size_t>(begin) * joint_count;
  const size_t last = static_cast<size_t>(end) * joint_count;
  out.rotations.assign(rotations.begin() + first, rotations.begin() + last);
  out.translations.assign(translations.begin() + first, translations.begin() + last);
  return out;
}

void permute_joints(Clip& clip, const std::vector<int>& order) {
  const Skeleton& old = clip.skeleton;
  const int joints = old.joint_count();
  if (static_cast<int>(order.size()) != joints) throw std::invalid_argument("permute_joints: order has the wrong size");
  std::vector<int> new_index(joints, -1);
  for (int i = 0; i < joints; ++i) new_index.at(order[i]) = i;
  Skeleton s;
  for (int i = 0; i < joints; ++i) {
    const int j = order[i];
    const int parent = old.parents[j] < 0 ? -1 : new_index[old.parents[j]];
    s.add_joint(old.names[j], parent, old.offsets[j], old.channels[j]);
  }
  for (EndSite site : old.end_sites) {
    site.parent = new_index[site.parent];
    s.end_sites.push_back(site);
  }
  s.validate();
  Motion m = clip.motion;
  for (int t = 0; t < m.frame_count; ++t) {
    for (int i = 0; i < joints; ++i) {
      m.rotation(t, i) = clip.motion.rotation(t, order[i]);
      m.translation(t, i) = clip.motion.translation(t, order[i]);
    }
  }
  clip.skeleton = std::move(s);
  clip.motion = std::move(m);
}

}  // namespace nec
