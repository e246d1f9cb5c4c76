// Inverse kinematics for procedural motion (two-bone analytic, FABRIK, and
// positions -> local rotations relative to rest directions), plus the
// platform-independent random numbers that every zoo choice is drawn from.
#include "nec/zoo/motion_synthesis.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nec::zoo {
namespace {

// A unit vector perpendicular to v.
Vec3 any_perpendicular(const Vec3& v) {
  const Vec3 axis = std::abs(v.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return v.cross(axis).normalized();
}

}  // namespace

Vec3 two_bone_middle(const Vec3& root, const Vec3& target, double upper, double lower, const Vec3& pole) {
  Vec3 to_target = target - root;
  double distance = to_target.norm();
  const Vec3 axis = distance > 1e-12 ? Vec3(to_target / distance) : Vec3(pole.normalized());
  const double longest = upper + lower;
  const double shortest = std::abs(upper - lower);
  distance = std::clamp(distance, shortest + 1e-9 * longest, longest);
  // Law of cosines: the middle joint's projection on the axis and its height above it.
  const double along = (upper * upper - lower * lower + distance * distance) / (2.0 * distance);
  const double height = std::sqrt(std::max(0.0, upper * upper - along * along));
  Vec3 bend = pole - pole.dot(axis) * axis;
  bend = bend.norm() > 1e-9 ? Vec3(bend.normalized()) : any_perpendicular(axis);
  return root + axis * along + bend * height;
}

void fabrik(std::vector<Vec3>& positions, const std::vector<double>& lengths, const Vec3& target, int max_iterations,
            double tolerance) {
  const size_t n = positions.size();
  if (n < 2) return;
  if (lengths.size() + 1 != n) throw std::invalid_argument("fabrik: need one length per segment");
  double total = 0.0;
  for (double length : lengths) total += length;
  const Vec3 root = positions[0];
  // Places `to` at `length` from `from` along the current from->to direction.
  auto place = [](const Vec3& from, Vec3& to, double length) {
    const Vec3 d = to - from;
    const double norm = d.norm();
    to = norm > 1e-15 ? Vec3(from + d * (length / norm)) : from;
  };
  if ((target - root).norm() >= total) {
    const Vec3 direction = (target - root).normalized();
    for (size_t i = 0; i + 1 < n; ++i) positions[i + 1] = positions[i] + direction * lengths[i];
    return;
  }
  const double tolerance_abs = tolerance * std::max(total, 1e-12);
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    if (iteration > 0 && (positions[n - 1] - target).norm() <= tolerance_abs) break;
    positions[n - 1] = target;
    for (size_t i = n - 1; i-- > 0;) place(positions[i + 1], positions[i], lengths[i]);
    positions[0] = root;
    for (size_t i = 0; i + 1 < n; ++i) place(positions[i], positions[i + 1], lengths[i]);
  }
}

Quat aim_chain(const Skeleton& skeleton, const std::vector<int>& chain, const std::vector<Vec3>& positions,
               const Quat& parent_global, Quat* local_rotations) {
  Quat previous = parent_global;
  for (size_t k = 0; k + 1 < chain.size(); ++k) {
    const Vec3& rest = skeleton.offsets[chain[k + 1]];
    const Vec3 want = positions[k + 1] - positions[k];
    Quat global = previous;  // local identity: the bone keeps its rest direction in the parent's frame
    if (rest.norm() > 1e-12 && want.norm() > 1e-12) {
      global = (Quat::FromTwoVectors(previous * rest, want) * previous).normalized();
    }
    local_rotations[chain[k]] = (previous.conjugate() * global).normalized();
    previous = global;
  }
  return previous;
}

uint64_t mix_seed(uint64_t a, uint64_t b) {
  // SplitMix64's output function of a * gamma + b + 0x632BE59BD9B4E019 (mix64 adds one gamma itself).
  return mix64(a * kSplitMixGamma + b + (0x632BE59BD9B4E019ULL - kSplitMixGamma));
}

}  // namespace nec::zoo
