// Foot locking: pin planted feet and bend their legs to reach the pins.
#include "nec/fitting/foot_lock.h"

#include "nec/motion/kinematics.h"
#include "nec/motion/statistics.h"

#include "leg_reach.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace nec {
namespace {

using detail::Leg;
using detail::Positions;

struct Plant {
  int begin = 0, end = 0;  // frames [begin, end)
  Vec3 pin = Vec3::Zero();
};

// Plants of one foot: runs of at least min_plant_frames frames within the contact height of `ground` and
// slower than `contact_speed`, each pinned at the foot's median ground position over it, at its lowest height
// there.
std::vector<Plant> plants_of(const Positions& positions, int frames, int foot, double ground, double size,
                             double fps, double contact_speed, const FootLockOptions& options, double& slide_sum,
                             long& slide_frames) {
  const auto at = [&](int t) -> const Vec3& { return positions.at(t, foot); };
  std::vector<double> speed(frames, 0.0);
  std::vector<bool> down(frames, false);
  for (int t = 0; t < frames; ++t) {
    speed[t] = horizontal_speed(positions.data, positions.joints, foot, t, fps) / size;
    down[t] = (at(t).y() - ground) / size < options.contact_height && speed[t] < contact_speed;
  }
  std::vector<Plant> plants;
  for (int t = 0; t < frames;) {
    if (!down[t]) {
      ++t;
      continue;
    }
    Plant plant;
    plant.begin = t;
    while (t < frames && down[t]) ++t;
    plant.end = t;
    if (plant.end - plant.begin < options.min_plant_frames) continue;
    for (int u = plant.begin; u < plant.end; ++u) slide_sum += speed[u];
    slide_frames += plant.end - plant.begin;
    for (const int axis : {0, 2}) {
      std::vector<double> values;
      for (int u = plant.begin; u < plant.end; ++u) values.push_back(at(u)[axis]);
      plant.pin[axis] = median(values);
    }
    plant.pin.y() = at(plant.begin).y();
    for (int u = plant.begin; u < plant.end; ++u) plant.pin.y() = std::min(plant.pin.y(), at(u).y());
    plants.push_back(plant);
  }
  return plants;
}

// How much the pin of `plant` holds at frame t: 1 over the plant, fading linearly to 0 over blend_frames.
double pin_weight(const Plant& plant, int t, int blend_frames) {
  if (t >= plant.begin && t < plant.end) return 1.0;
  const int away = t < plant.begin ? plant.begin - t : t - plant.end + 1;
  return std::max(0.0, 1.0 - static_cast<double>(away) / (blend_frames + 1));
}

}  // namespace

void FootLockOptions::validate() const {
  if (!(contact_height > 0.0)) throw std::invalid_argument("contact_height must be positive");
  if (!(foot_height >= 0.0)) throw std::invalid_argument("foot_height must not be negative");
  if (!(contact_speed > 0.0)) throw std::invalid_argument("contact_speed must be positive");
  if (!(contact_speed_ratio >= 0.0)) throw std::invalid_argument("contact_speed_ratio must not be negative");
  if (min_plant_frames < 1) throw std::invalid_argument("min_plant_frames must be at least 1");
  if (blend_frames < 0) throw std::invalid_argument("blend_frames must not be negative");
}

FootLockReport lock_feet(const Skeleton& skeleton, Motion& motion, const FootLockOptions& options) {
  options.validate();
  if (motion.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument("lock_feet: motion has " + std::to_string(motion.joint_count) +
                                " joints, skeleton has " + std::to_string(skeleton.joint_count()));
  }
  FootLockReport report;
  const int frames = motion.frame_count, joints = motion.joint_count;
  const double size = skeleton.diameter();
  if (frames < 2 || !(size > 0.0)) return report;

  Positions positions{{}, joints};
  joint_positions(skeleton, motion, positions.data);
  const std::vector<double> lowest = lowest_joint_heights(positions.data, joints);
  double root_path = 0.0;  // horizontal
  for (int t = 1; t < frames; ++t) {
    Vec3 step = positions.at(t, 0) - positions.at(t - 1, 0);
    step.y() = 0.0;
    root_path += step.norm();
  }
  const double floor = median(lowest);
  const double root_speed = root_path / size * motion.fps / (frames - 1);
  const double contact_speed = std::max(options.contact_speed, options.contact_speed_ratio * root_speed);

  // Feet and their plants; two feet on one leg (toes of one paw) would fight: the first keeps it.
  const std::vector<std::vector<int>> children = skeleton.children_lists();
  std::vector<Leg> legs;
  std::vector<std::vector<Plant>> plants;
  std::vector<bool> hip_taken(joints, false);
  double slide_sum = 0.0;
  long slide_frames = 0;
  for (const int leaf : skeleton.leaves()) {
    const Leg leg = detail::leg_above(skeleton, children, leaf);
    if (leg.hip < 0 || hip_taken[leg.hip]) continue;
    const double ground = detail::foot_ground(positions, frames, leaf);
    if ((ground - floor) / size > options.foot_height) continue;
    std::vector<Plant> found =
        plants_of(positions, frames, leaf, ground, size, motion.fps, contact_speed, options, slide_sum, slide_frames);
    if (found.empty()) continue;
    hip_taken[leg.hip] = true;
    legs.push_back(leg);
    plants.push_back(std::move(found));
    report.planted_spans += static_cast<int>(plants.back().size());
  }
  report.feet = static_cast<int>(legs.size());
  if (legs.empty()) return report;
  report.mean_slide = slide_sum / static_cast<double>(slide_frames);

  // Per frame and foot, its strongest plant: the pin over the plant; around it, the shift that the pin made
  // at the plant's nearer end, fading.
  detail::LegTargets targets(legs.size(), std::vector<std::pair<double, Vec3>>(frames));
  for (size_t k = 0; k < legs.size(); ++k) {
    const auto was = [&](int t) -> const Vec3& { return positions.at(t, legs[k].foot); };
    for (int t = 0; t < frames; ++t) {
      targets[k][t] = {0.0, was(t)};
      for (const Plant& plant : plants[k]) {
        const double w = pin_weight(plant, t, options.blend_frames);
        if (w <= targets[k][t].first) continue;
        const int end = t < plant.begin ? plant.begin : std::min(t, plant.end - 1);
        targets[k][t] = {w, was(t) + w * (plant.pin - was(end))};
      }
    }
  }
  report.max_miss = detail::reach_targets(skeleton, motion, legs, targets, positions, size);
  return report;
}

}  // namespace nec
