// Legs and two-bone reaching (leg_reach.h).
#include "leg_reach.h"

#include <algorithm>
#include <cmath>

namespace nec::detail {
namespace {

constexpr int kMaxLegJoints = 4;

// Sets joint j's local rotation so that its global rotation becomes `global`.
void set_global_rotation(const Skeleton& skeleton, const Pose& pose, Motion& motion, int t, int j,
                         const Quat& global) {
  const Quat parent = pose.rotation(t, skeleton.parents[j]);
  motion.rotation(t, j) = (parent.conjugate() * global).normalized();
}

}  // namespace

Leg leg_above(const Skeleton& skeleton, const std::vector<std::vector<int>>& children, int foot) {
  std::vector<int> chain;  // from the foot's parent upwards
  for (int j = skeleton.parents[foot]; j > 0 && static_cast<int>(chain.size()) < kMaxLegJoints;
       j = skeleton.parents[j]) {
    chain.push_back(j);
    if (children[skeleton.parents[j]].size() > 1) break;
  }
  Leg leg;
  leg.foot = foot;
  if (chain.empty()) return leg;
  leg.hip = chain.back();
  if (chain.size() > 1) leg.knee = chain[(chain.size() - 1) / 2];
  return leg;
}

double foot_ground(const Positions& positions, int frames, int foot) {
  std::vector<double> heights(frames);
  for (int t = 0; t < frames; ++t) heights[t] = positions.at(t, foot).y();
  std::nth_element(heights.begin(), heights.begin() + frames / 10, heights.end());
  return heights[frames / 10];
}

void reach(const Skeleton& skeleton, const Pose& pose, Motion& motion, int t, const Leg& leg, const Vec3& target) {
  const Vec3 hip = pose.position(t, leg.hip);
  Vec3 foot = pose.position(t, leg.foot);
  if (leg.knee >= 0) {
    const Vec3 knee = pose.position(t, leg.knee);
    const double a = (hip - knee).norm(), b = (foot - knee).norm();
    const Vec3 n = (hip - knee).cross(foot - knee);
    if (a > 1e-9 && b > 1e-9 && n.norm() > 1e-9 * a * b) {
      const double d = std::clamp((target - hip).norm(), std::abs(a - b), a + b);
      const double bend = std::acos(std::clamp((hip - knee).dot(foot - knee) / (a * b), -1.0, 1.0));
      const double wanted = std::acos(std::clamp((a * a + b * b - d * d) / (2.0 * a * b), -1.0, 1.0));
      const Quat knee_turn(Eigen::AngleAxisd(wanted - bend, n.normalized()));
      set_global_rotation(skeleton, pose, motion, t, leg.knee, knee_turn * pose.rotation(t, leg.knee));
      foot = knee + knee_turn * (foot - knee);
    }
  }
  const Quat swing = Quat::FromTwoVectors(foot - hip, target - hip);
  // The hip's parent is above the leg and keeps its rotation; the knee's local rotation, set above, turns
  // with the hip.
  set_global_rotation(skeleton, pose, motion, t, leg.hip, swing * pose.rotation(t, leg.hip));
}

double reach_targets(const Skeleton& skeleton, Motion& motion, const std::vector<Leg>& legs, const LegTargets& targets,
                     Positions& positions, double size) {
  for (size_t k = 0; k < legs.size(); ++k) {
    const bool has_target = std::any_of(targets[k].begin(), targets[k].end(), [](const auto& w) { return w.first > 0.0; });
    if (!has_target) continue;  // forward kinematics only for the legs that move
    const Pose pose = forward_kinematics(skeleton, motion);
    for (int t = 0; t < motion.frame_count; ++t) {
      if (targets[k][t].first > 0.0) reach(skeleton, pose, motion, t, legs[k], targets[k][t].second);
    }
  }
  joint_positions(skeleton, motion, positions.data);
  double miss = 0.0;
  for (size_t k = 0; k < legs.size(); ++k) {
    for (int t = 0; t < motion.frame_count; ++t) {
      if (targets[k][t].first < 1.0) continue;
      miss = std::max(miss, (positions.at(t, legs[k].foot) - targets[k][t].second).norm() / size);
    }
  }
  return miss;
}

}  // namespace nec::detail
