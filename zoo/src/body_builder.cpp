// Builders every body plan shares (body_plans.h): geometry helpers, the body
// under construction (chains, end sites, mirrored limbs), legs fitted so
// that their last joint lands on the ground, and wing chains.
#include "body_plans.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nec::zoo::detail {
namespace {

// A bone's lean (degrees from straight down towards `out`) when the leg splays
// `splay` degrees further out. Bones leaning out stay between straight down and
// (almost) straight up; a bone leaning back (negative: a vertebrate's shin
// going down and back from a knee bent forward) keeps its lean, it never splays.
double bone_lean(const LegBone& bone, double splay) {
  return bone.degrees < 0.0 ? std::max(bone.degrees, -178.0) : std::clamp(bone.degrees + splay, 0.0, 178.0);
}

double leg_length(const std::vector<LegBone>& bones) {
  double length = 0.0;
  for (const LegBone& bone : bones) length += bone.length;
  return length;
}

}  // namespace

// ---- geometry helpers ----

Vec3 horizontal(double yaw_degrees) {
  return Vec3(std::sin(radians(yaw_degrees)), 0.0, std::cos(radians(yaw_degrees)));
}

Vec3 elevated(const Vec3& direction, double degrees) {
  return direction * std::cos(radians(degrees)) + Vec3::UnitY() * std::sin(radians(degrees));
}

Vec3 down_toward(const Vec3& out, double degrees) {
  return out * std::sin(radians(degrees)) - Vec3::UnitY() * std::cos(radians(degrees));
}

std::vector<Vec3> walk(const Vec3& start, const std::vector<Vec3>& steps) {
  std::vector<Vec3> points{start};
  for (const Vec3& step : steps) points.push_back(points.back() + step);
  return points;
}

std::vector<Vec3> curled_chain(const Vec3& start, const Vec3& direction, double elevation_degrees,
                               double curl_degrees, int count, double length) {
  std::vector<Vec3> steps;
  for (int k = 0; k < count; ++k) {
    steps.push_back(elevated(direction, elevation_degrees + curl_degrees * k) * (length / count));
  }
  return walk(start, steps);
}

Vec3 split_neck(std::vector<Vec3>& points) {
  const Vec3 head = points.back();
  points.pop_back();
  for (size_t k = 0; k < points.size(); ++k) {
    const Vec3 next = k + 1 < points.size() ? points[k + 1] : head;
    points[k] += 0.3 * (next - points[k]);
  }
  return head;
}

void keep_above(std::vector<Vec3>& points, double floor) {
  const double base = points.front().y();
  double lowest = base;
  for (const Vec3& p : points) lowest = std::min(lowest, p.y());
  if (lowest >= floor || base <= floor) return;
  const double squash = (base - floor) / (base - lowest);
  for (Vec3& p : points) p.y() = base + (p.y() - base) * squash;
}

double droop_within(double wanted, double height, double length) {
  const double limit = std::asin(std::clamp(0.9 * height / length, 0.0, 1.0)) * 180.0 / kPi;
  return std::min(wanted, limit);
}

Vec3 spread(const Vec3& out, RestPose pose, double droop_limit) {
  return pose == RestPose::TPose ? out : elevated(out, -std::min(45.0, droop_limit));
}

// ---- the body under construction ----

std::vector<int> Body::add_chain(int parent, const std::vector<JointSpec>& specs, const std::vector<Vec3>& points) {
  if (points.size() != specs.size() && points.size() != specs.size() + 1) {
    throw std::logic_error("add_chain: need one point per joint, plus one for an end site");
  }
  std::vector<int> chain;
  for (size_t k = 0; k < specs.size(); ++k) {
    parent = add(specs[k], parent, points[k]);
    chain.push_back(parent);
  }
  if (points.size() > specs.size()) end(parent, points.back());
  return chain;
}

std::vector<int> Body::mirror(const std::vector<int>& left) {
  std::vector<int> right;
  auto mapped = [&](int joint) {
    const auto it = std::find(left.begin(), left.end(), joint);
    return it == left.end() ? joint : right[static_cast<size_t>(it - left.begin())];
  };
  for (int joint : left) {
    JointSpec copy = joints[joint].spec;
    copy.side = Side::Right;
    Vec3 position = joints[joint].position;
    position.x() = -position.x();
    right.push_back(add(copy, mapped(joints[joint].parent), position));
  }
  const size_t end_count = ends.size();
  for (size_t e = 0; e < end_count; ++e) {
    if (std::find(left.begin(), left.end(), ends[e].parent) == left.end()) continue;
    Vec3 position = ends[e].position;
    position.x() = -position.x();
    end(mapped(ends[e].parent), position);
  }
  return right;
}

void Body::limb(LimbKind kind, Side side, int pair, std::vector<int> chain) {
  if (chain.empty()) return;
  Limb l;
  l.kind = kind;
  l.side = side;
  l.pair = pair;
  l.joints = std::move(chain);
  limbs.push_back(std::move(l));
}

void Body::paired_limb(LimbKind kind, int pair, const std::vector<int>& left) {
  const std::vector<int> right = mirror(left);
  limb(kind, Side::Left, pair, left);
  limb(kind, Side::Right, pair, right);
}

// ---- legs ----
//
// Legs are built on the left and mirrored (x negated), so both sides are
// exactly symmetric. A leg is a list of bones, each leaning from straight down
// towards a horizontal direction by an angle that depends on the rest pose;
// the bones are fitted so that the leg's last joint lands on y = 0.

double leg_drop(const std::vector<LegBone>& bones, double splay) {
  double drop = 0.0;
  for (const LegBone& bone : bones) drop += bone.length * std::cos(radians(bone_lean(bone, splay)));
  return drop;
}

void turn_leg_to_reach(std::vector<LegBone>& bones, double ahead) {
  double along = 0.0, down = 0.0;
  for (const LegBone& bone : bones) {
    along += bone.length * std::sin(radians(bone.degrees));
    down += bone.length * std::cos(radians(bone.degrees));
  }
  // Turned by t: along cos t + down sin t = reach sin(t + phase).
  const double reach = std::hypot(along, down);
  if (!(reach > 0.0)) return;
  const double phase = std::atan2(along, down);
  const double turn = std::asin(std::clamp(ahead / reach, -1.0, 1.0)) - phase;
  for (LegBone& bone : bones) bone.degrees += turn * 180.0 / kPi;
}

std::vector<int> add_leg(Body& body, int parent, const Vec3& hip, LegShape shape, LegFit fit) {
  const double target = hip.y();
  double splay = 0.0;
  if (fit == LegFit::Splay && std::abs(leg_drop(shape.bones) - target) > 1e-12 * target) {
    double lo = -60.0, hi = 60.0;  // drop decreases as the leg splays out
    if (leg_drop(shape.bones, lo) >= target && leg_drop(shape.bones, hi) <= target) {
      for (int iteration = 0; iteration < 80; ++iteration) {
        const double mid = 0.5 * (lo + hi);
        (leg_drop(shape.bones, mid) > target ? lo : hi) = mid;
      }
      splay = 0.5 * (lo + hi);
    }
  }
  const double drop = leg_drop(shape.bones, splay);
  if (!(drop > 1e-6 * leg_length(shape.bones))) throw std::logic_error("add_leg: the leg does not reach down");
  const double scale = target / drop;
  std::vector<Vec3> steps;
  for (const LegBone& bone : shape.bones) {
    steps.push_back(down_toward(shape.out, bone_lean(bone, splay)) * (bone.length * scale));
  }
  std::vector<Vec3> points = walk(hip, steps);
  points.back().y() = 0.0;
  points.push_back(points.back() + shape.end_direction * (shape.end_length * scale));
  return body.add_chain(parent, shape.joints, points);
}

std::vector<JointSpec> leg_specs(const std::vector<Part>& parts, const std::string& qualifier, int pair_number) {
  std::vector<JointSpec> specs;
  for (size_t k = 0; k < parts.size(); ++k) {
    JointSpec s = spec(parts[k], Side::Left, qualifier);
    s.pair = pair_number;
    s.segment = static_cast<int>(k);
    specs.push_back(s);
  }
  return specs;
}

// ---- wings ----

std::vector<int> add_wing(Body& body, int parent, const Vec3& root, const std::vector<Vec3>& directions,
                          const std::vector<double>& lengths, const std::vector<Part>& parts, double wing,
                          double floor) {
  std::vector<Vec3> steps;
  for (size_t b = 0; b < lengths.size(); ++b) steps.push_back(directions[b].normalized() * (lengths[b] * wing));
  std::vector<Vec3> points = walk(root, steps);
  keep_above(points, floor);
  std::vector<JointSpec> specs;
  for (Part part : parts) specs.push_back(spec(part, Side::Left));
  return body.add_chain(parent, specs, points);
}

}  // namespace nec::zoo::detail
