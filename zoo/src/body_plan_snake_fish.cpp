// Legless body plans: the snake (lying on the ground; crouched: raised like a
// cobra) and the fish (spine, tail and fins, resting on its lowest fin).
#include "body_plans.h"

#include <algorithm>
#include <cmath>

namespace nec::zoo::detail {
namespace {

// Fin chain: `count` joints of total `length` along `direction` from `base`.
std::vector<int> add_fin(Body& body, int parent, const Vec3& base, const Vec3& direction, double length, int count,
                         Side side, const std::string& qualifier) {
  std::vector<Vec3> steps(static_cast<size_t>(count), direction.normalized() * (length / count));
  return body.add_chain(parent, chain_specs(Part::Fin, count, side, qualifier), walk(base, steps));
}

}  // namespace

void build_fish(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "fish";
  const double length = rng.uniform(0.25, 1.5);  // snout to tail fin
  const int spine_count = rng.integer(1, 2);
  const int tail_count = rng.integer(3, 8);
  const int caudal_count = rng.integer(1, 2);
  const int pectoral_count = rng.integer(1, 2);
  const int dorsal_count = rng.integer(1, 2);
  const bool jaw = rng.chance(0.5);
  const bool pelvic = rng.chance(0.5);
  const bool anal = rng.chance(0.4);
  const double fin = length * rng.uniform(0.10, 0.14);
  const bool folded = pose == RestPose::Crouched;

  // Built with the root at the origin; the finish lifts the lowest fin tip to y = 0.
  body.add(spec(Part::Hips), -1, Vec3::Zero());
  std::vector<Vec3> spine_points;
  for (int k = 1; k <= spine_count; ++k) spine_points.push_back(Vec3(0.0, 0.0, 0.13 * length * k / spine_count));
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, spine_count), spine_points);
  const int chest = spine.back();
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);
  const Vec3 head_position(0.0, 0.01 * length, 0.22 * length);
  const int head_joint = body.add(spec(Part::Head), chest, head_position);
  body.head_tip = Vec3(0.0, 0.0, 0.45 * length);
  body.end(head_joint, body.head_tip);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {
    body.limb(LimbKind::Jaw, Side::None, 0,
              body.add_chain(head_joint, {spec(Part::Jaw)},
                             {Vec3(0.0, -0.03, 0.3) * length, Vec3(0.0, -0.04, 0.43) * length}));
  }
  std::vector<Vec3> tail_points;
  for (int k = 0; k < tail_count; ++k) tail_points.push_back(Vec3(0.0, 0.0, -(0.1 + 0.35 * k / (tail_count - 1)) * length));
  const std::vector<int> tail = body.add_chain(0, chain_specs(Part::Tail, tail_count), tail_points);
  body.limb(LimbKind::Tail, Side::None, 0, tail);

  // Fins, indexed front to back in Limb::pair: pectoral 0, dorsal 1, pelvic 2, anal 3, caudal 4.
  const Vec3 pectoral_direction = folded ? Vec3(0.25, -0.15, -1.0) : spread(Vec3(1.0, 0.0, -0.3).normalized(), pose);
  body.paired_limb(LimbKind::Fin, 0,
                   add_fin(body, chest, body.at(chest) + Vec3(0.05, -0.04, 0.0) * length, pectoral_direction, fin,
                           pectoral_count, Side::Left, "pectoral"));
  body.limb(LimbKind::Fin, Side::None, 1,
            add_fin(body, 0, Vec3(0.0, 0.08, -0.02) * length, folded ? Vec3(0.0, 0.3, -1.0) : Vec3(0.0, 0.8, -0.6),
                    fin, dorsal_count, Side::None, "dorsal"));
  if (pelvic) {
    body.paired_limb(LimbKind::Fin, 2,
                     add_fin(body, 0, Vec3(0.03, -0.07, -0.05) * length,
                             folded ? Vec3(0.15, -0.3, -1.0) : Vec3(0.3, -0.8, -0.5), 0.7 * fin, 1, Side::Left, "pelvic"));
  }
  if (anal) {
    body.limb(LimbKind::Fin, Side::None, 3,
              add_fin(body, tail.front(), body.at(tail.front()) + Vec3(0.0, -0.06, -0.02) * length,
                      folded ? Vec3(0.0, -0.3, -1.0) : Vec3(0.0, -0.7, -0.7), 0.6 * fin, 1, Side::None, "anal"));
  }
  std::vector<Vec3> caudal_steps(static_cast<size_t>(caudal_count), Vec3(0.0, 0.0, -0.06 * length / caudal_count));
  caudal_steps.push_back(Vec3(0.0, 0.0, -0.04 * length));
  std::vector<Vec3> caudal_points = walk(body.at(tail.back()), caudal_steps);
  caudal_points.erase(caudal_points.begin());  // the last tail joint
  body.limb(LimbKind::Fin, Side::None, 4,
            body.add_chain(tail.back(), chain_specs(Part::Fin, caudal_count, Side::None, "caudal"), caudal_points));
  body.tail_tip = caudal_points.back();
}

void build_snake(Body& body, SplitMix64& rng, RestPose pose) {
  body.species = "snake";
  const int total = rng.integer(20, 60);  // joints without the jaw
  const double length = rng.uniform(0.8, 3.5);
  const int neck_count = rng.integer(1, 3);
  const int tail_count = static_cast<int>(std::lround(total * rng.uniform(0.2, 0.3)));
  const int front_count = total - 1 - tail_count - neck_count - 1;
  const bool jaw = rng.chance(0.5);
  const double segment = length / (total + 1.5);

  // Lying on the ground (the root too, so rest_root_height is 0); crouched
  // raises the neck and head like a cobra.
  body.add(spec(Part::Hips), -1, Vec3::Zero());
  const int raised = pose == RestPose::Crouched ? 3 + neck_count + 1 : 0;  // segments ahead of the raise
  std::vector<Vec3> steps;
  const int ahead = front_count + neck_count + 1;
  for (int k = 0; k < ahead; ++k) {
    const int into_raise = k - (ahead - raised);
    const double degrees = into_raise >= 0 ? std::min(50.0, 15.0 * (into_raise + 1)) : 0.0;
    steps.push_back(elevated(Vec3::UnitZ(), degrees) * segment);
  }
  std::vector<Vec3> points = walk(Vec3::Zero(), steps);
  points.erase(points.begin());  // the root
  const std::vector<int> spine = body.add_chain(0, chain_specs(Part::Spine, front_count),
                                                std::vector<Vec3>(points.begin(), points.begin() + front_count));
  const std::vector<int> necks = body.add_chain(
      spine.back(), chain_specs(Part::Neck, neck_count),
      std::vector<Vec3>(points.begin() + front_count, points.begin() + front_count + neck_count));
  const Vec3 head_position = points.back();
  const Vec3 head_direction = (points.back() - points[points.size() - 2]).normalized();
  const int head_joint = body.add(spec(Part::Head), necks.back(), head_position);
  body.head_tip = head_position + head_direction * (1.5 * segment);
  body.end(head_joint, body.head_tip);
  body.spine.insert(body.spine.end(), spine.begin(), spine.end());
  body.limb(LimbKind::Spine, Side::None, 0, spine);
  body.limb(LimbKind::Neck, Side::None, 0, necks);
  body.limb(LimbKind::Head, Side::None, 0, {head_joint});
  if (jaw) {
    const Vec3 jaw_position = head_position + head_direction * (0.3 * segment);
    body.limb(
        LimbKind::Jaw, Side::None, 0,
        body.add_chain(head_joint, {spec(Part::Jaw)}, {jaw_position, jaw_position + head_direction * (0.9 * segment)}));
  }
  std::vector<Vec3> tail_points;
  for (int k = 1; k <= tail_count + 1; ++k)
    tail_points.push_back(Vec3(0.0, 0.0, -segment * (k <= tail_count ? k : k - 0.3)));
  body.tail_tip = tail_points.back();
  body.limb(LimbKind::Tail, Side::None, 0, body.add_chain(0, chain_specs(Part::Tail, tail_count), tail_points));
}

}  // namespace nec::zoo::detail
