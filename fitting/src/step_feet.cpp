// Stepping after a source: gliding feet put down in the source's rhythm.
#include "nec/fitting/step_feet.h"

#include "nec/motion/kinematics.h"
#include "nec/motion/rotations.h"
#include "nec/motion/kinematic_signals.h"
#include "nec/motion/statistics.h"
#include "nec/fitting/transfer_check.h"

#include "leg_reach.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace nec {
namespace {

using detail::Leg;
using detail::Positions;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kFootHeight = 0.1;  // body sizes: a foot's ground is at most this above the floor (as foot locking)

// Where a foot sits on the body: its mean horizontal offset from the root over frames [begin, end), in the
// facing frame (heading in degrees about +Y, 0 facing +Z; left is (cos h, 0, -sin h)).
struct Placement {
  double forward = 0.0;
  double left = 0.0;
};

Placement placement_of(const Positions& positions, const std::vector<double>& heading, int foot, int begin, int end) {
  Placement p;
  for (int t = begin; t < end; ++t) {
    const Vec3 offset = positions.at(t, foot) - positions.at(t, 0);
    const double h = heading[t] / kDegreesPerRadian;
    p.forward += offset.x() * std::sin(h) + offset.z() * std::cos(h);
    p.left += offset.x() * std::cos(h) - offset.z() * std::sin(h);
  }
  const double n = std::max(1, end - begin);
  p.forward /= n;
  p.left /= n;
  return p;
}

// Phase offsets in [0, 1): left feet 0 .. 1/2, right feet 1/2 .. 1, back to front in equal shares; NaN for
// feet near the midline.
std::vector<double> phase_offsets(const std::vector<Placement>& placements, double midline) {
  double widest = 0.0;
  for (const Placement& p : placements) widest = std::max(widest, std::abs(p.left));
  std::vector<int> left, right;
  for (int i = 0; i < static_cast<int>(placements.size()); ++i) {
    if (!(std::abs(placements[i].left) > midline * widest)) continue;
    (placements[i].left > 0.0 ? left : right).push_back(i);
  }
  std::vector<double> offsets(placements.size(), kNaN);
  for (const auto& [side, base] : {std::pair{&left, 0.0}, std::pair{&right, 0.5}}) {
    std::stable_sort(side->begin(), side->end(),
                     [&](int a, int b) { return placements[a].forward < placements[b].forward; });
    for (size_t k = 0; k < side->size(); ++k) offsets[(*side)[k]] = base + 0.5 * k / side->size();
  }
  return offsets;
}

double fraction(double x) { return x - std::floor(x); }

// The source's rhythm: a phase per frame (a stride is one unit; the reference foot touches down at its offset
// plus a whole number), the frames [begin, end) over which it steps, and its duty factor.
struct Rhythm {
  bool steps = false;
  std::vector<double> phase;
  int begin = 0, end = 0;
  double duty = 0.0;
  double strides_per_second = 0.0;
  double reference_offset = 0.0;  // the reference foot's phase offset
};

Rhythm rhythm_of(const Clip& source, const StepOptions& options) {
  const Motion& m = source.motion;
  const int frames = m.frame_count, joints = m.joint_count;
  const double size = source.skeleton.diameter();
  Rhythm rhythm;
  Positions positions{{}, joints};
  joint_positions(source.skeleton, m, positions.data);
  const double floor = lowest_height(positions.data);

  std::vector<int> feet;
  std::vector<std::vector<int>> touchdowns;
  std::vector<double> periods, duties;
  for (const int leaf : source.skeleton.leaves()) {
    const std::vector<bool> contact = contact_frames(positions.data, joints, leaf, floor, size, m.fps);
    std::vector<int> down = touchdown_frames(contact);
    if (down.size() < 2) continue;
    std::vector<double> gaps;
    for (size_t k = 1; k < down.size(); ++k) gaps.push_back(down[k] - down[k - 1]);
    periods.push_back(median(gaps));
    duties.push_back(static_cast<double>(std::count(contact.begin() + down.front(), contact.begin() + down.back(), true)) /
                     (down.back() - down.front()));
    feet.push_back(leaf);
    touchdowns.push_back(std::move(down));
  }
  if (feet.empty()) return rhythm;

  const std::vector<double> heading = measure_heading(source);
  std::vector<Placement> placements;
  for (const int foot : feet) placements.push_back(placement_of(positions, heading, foot, 0, frames));
  const std::vector<double> offsets = phase_offsets(placements, options.midline);
  size_t reference = 0;  // the smallest offset; the first stepping foot when every foot is on the midline
  for (size_t i = 0; i < feet.size(); ++i) {
    if (!std::isnan(offsets[i]) && (std::isnan(offsets[reference]) || offsets[i] < offsets[reference])) reference = i;
  }
  const double offset = std::isnan(offsets[reference]) ? 0.0 : offsets[reference];
  rhythm.reference_offset = offset;
  const std::vector<int>& down = touchdowns[reference];
  const double period = periods[reference];
  rhythm.phase.resize(frames);
  for (int t = 0; t < frames; ++t) {
    if (t <= down.front()) {
      rhythm.phase[t] = offset + (t - down.front()) / period;
    } else if (t >= down.back()) {
      rhythm.phase[t] = offset + static_cast<double>(down.size() - 1) + (t - down.back()) / period;
    } else {
      const size_t k = std::upper_bound(down.begin(), down.end(), t) - down.begin() - 1;
      rhythm.phase[t] = offset + static_cast<double>(k) + static_cast<double>(t - down[k]) / (down[k + 1] - down[k]);
    }
  }
  rhythm.duty = std::clamp(median(duties), 0.3, 0.85);
  rhythm.strides_per_second = m.fps / median(periods);
  int first = frames, last = 0;
  for (const std::vector<int>& d : touchdowns) first = std::min(first, d.front()), last = std::max(last, d.back());
  rhythm.begin = std::max(0, first - static_cast<int>(std::lround((1.0 - rhythm.duty) * period)));
  rhythm.end = std::min(frames, last + static_cast<int>(std::lround(rhythm.duty * period)));
  rhythm.steps = rhythm.end - rhythm.begin >= 2;
  return rhythm;
}

struct Plant {
  int begin = 0, end = 0;  // frames [begin, end)
  Vec3 pin = Vec3::Zero();
};

// The slowest cadence (strides per second) at which the body travels at most `stance` times the leg's
// stretched length (hip to foot) over one plant of duty / cadence seconds, at its mean horizontal speed over
// the stepping span; 0 for a body that does not travel.
double reachable_cadence(const Skeleton& skeleton, const Positions& positions, const Leg& leg, const Rhythm& rhythm,
                         double fps, double stance) {
  double length = 0.0;
  for (int j = leg.foot; j != leg.hip; j = skeleton.parents[j]) length += skeleton.offsets[j].norm();
  double path = 0.0;
  for (int t = std::max(rhythm.begin, 1); t < rhythm.end; ++t) {
    Vec3 step = positions.at(t, 0) - positions.at(t - 1, 0);
    step.y() = 0.0;
    path += step.norm();
  }
  const int frames = rhythm.end - std::max(rhythm.begin, 1);
  if (frames <= 0 || !(length > 0.0)) return 0.0;
  const double speed = path / frames * fps;
  return speed * rhythm.duty / (stance * length);
}

double smoothstep(double s) { return s * s * (3.0 - 2.0 * s); }

}  // namespace

void StepOptions::validate() const {
  if (!(glide_ratio > 0.0)) throw std::invalid_argument("glide_ratio must be positive");
  if (!(lift_ratio >= 0.0)) throw std::invalid_argument("lift_ratio must not be negative");
  if (!(min_lift >= 0.0)) throw std::invalid_argument("min_lift must not be negative");
  if (!(midline >= 0.0 && midline < 1.0)) throw std::invalid_argument("midline must be in [0, 1)");
  if (!(stance > 0.0)) throw std::invalid_argument("stance must be positive");
  if (blend_frames < 0) throw std::invalid_argument("blend_frames must not be negative");
}

StepReport step_after(const Clip& source, const Skeleton& skeleton, Motion& motion, const StepOptions& options) {
  options.validate();
  if (motion.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument("step_after: motion has " + std::to_string(motion.joint_count) +
                                " joints, skeleton has " + std::to_string(skeleton.joint_count()));
  }
  if (source.motion.frame_count != motion.frame_count || std::abs(source.motion.fps - motion.fps) > 1e-9) {
    throw std::invalid_argument("step_after: the source has " + std::to_string(source.motion.frame_count) +
                                " frames at " + std::to_string(source.motion.fps) + " fps, the motion " +
                                std::to_string(motion.frame_count) + " at " + std::to_string(motion.fps));
  }
  StepReport report;
  const int frames = motion.frame_count, joints = motion.joint_count;
  const double size = skeleton.diameter();
  if (frames < 3 || !(size > 0.0) || !(source.skeleton.diameter() > 0.0)) return report;
  const Rhythm rhythm = rhythm_of(source, options);
  if (!rhythm.steps) return report;
  report.source_strides_per_second = rhythm.strides_per_second;
  report.duty = rhythm.duty;

  Positions positions{{}, joints};
  joint_positions(skeleton, motion, positions.data);
  const double floor = lowest_height(positions.data);
  const double standing = median(lowest_joint_heights(positions.data, joints));

  // The gliding feet, one per leg (the toes of one paw would fight: the first keeps the leg).
  const std::vector<std::vector<int>> children = skeleton.children_lists();
  std::vector<Leg> legs;
  std::vector<double> grounds;
  std::vector<bool> hip_taken(joints, false);
  const int span = rhythm.end - rhythm.begin;
  for (const int leaf : skeleton.leaves()) {
    const Leg leg = detail::leg_above(skeleton, children, leaf);
    if (leg.hip < 0 || hip_taken[leg.hip]) continue;
    const double ground = detail::foot_ground(positions, frames, leaf);
    if ((ground - standing) / size > kFootHeight) continue;
    hip_taken[leg.hip] = true;
    const std::vector<bool> contact = contact_frames(positions.data, joints, leaf, floor, size, motion.fps);
    const double down = static_cast<double>(
        std::count(contact.begin() + rhythm.begin, contact.begin() + rhythm.end, true)) / span;
    if (down >= options.glide_ratio * rhythm.duty) continue;
    legs.push_back(leg);
    grounds.push_back(ground);
  }
  if (legs.empty()) return report;
  const std::vector<double> heading = measure_heading(Clip{skeleton, motion, {}});
  std::vector<Placement> placements;
  for (const Leg& leg : legs) placements.push_back(placement_of(positions, heading, leg.foot, rhythm.begin, rhythm.end));
  const std::vector<double> offsets = phase_offsets(placements, options.midline);

  // The cadence: the source's, or faster where a plant would carry the body too far over a leg.
  double cadence = rhythm.strides_per_second;
  for (size_t k = 0; k < legs.size(); ++k) {
    if (std::isnan(offsets[k])) continue;
    cadence = std::max(cadence, reachable_cadence(skeleton, positions, legs[k], rhythm, motion.fps, options.stance));
  }
  const double speedup = cadence / rhythm.strides_per_second;
  report.strides_per_second = cadence;
  const auto phase = [&](int t) {
    return rhythm.reference_offset + (rhythm.phase[t] - rhythm.reference_offset) * speedup;
  };

  // Per foot and frame: the target and how much it holds (1 over plants and swings, fading at the ends).
  detail::LegTargets targets(legs.size());
  for (size_t k = 0; k < legs.size(); ++k) {
    targets[k].assign(frames, {0.0, Vec3::Zero()});
    if (std::isnan(offsets[k])) continue;
    const Leg& leg = legs[k];
    const auto was = [&](int t) -> const Vec3& { return positions.at(t, leg.foot); };
    std::vector<Plant> plants;
    for (int t = rhythm.begin; t < rhythm.end;) {
      if (!(fraction(phase(t) - offsets[k]) < rhythm.duty)) {
        ++t;
        continue;
      }
      Plant plant;
      plant.begin = t;
      while (t < rhythm.end && fraction(phase(t) - offsets[k]) < rhythm.duty) ++t;
      plant.end = t;
      if (plant.end - plant.begin < 2) continue;
      plant.pin = was((plant.begin + plant.end) / 2);
      plant.pin.y() = grounds[k];
      plants.push_back(plant);
    }
    if (plants.empty()) continue;
    double hip_height = 0.0;
    for (int t = rhythm.begin; t < rhythm.end; ++t) hip_height += positions.at(t, leg.hip).y() - grounds[k];
    hip_height /= span;
    const double lift = std::min(std::max(options.lift_ratio * hip_height, options.min_lift * size), 0.5 * hip_height);
    for (size_t p = 0; p < plants.size(); ++p) {
      const Plant& plant = plants[p];
      for (int t = plant.begin; t < plant.end; ++t) targets[k][t] = {1.0, plant.pin};
      if (p + 1 == plants.size()) break;
      const Plant& next = plants[p + 1];
      const double from = plant.end - 1, length = next.begin - from;
      for (int t = plant.end; t < next.begin; ++t) {
        const double s = (t - from) / length;
        Vec3 at = plant.pin + smoothstep(s) * (next.pin - plant.pin);
        at.y() = grounds[k] + lift * std::sin(M_PI * s);
        targets[k][t] = {1.0, at};
      }
    }
    // Into the first pin and out of the last: the pin's shift fades as foot locking's does.
    const Plant& first = plants.front();
    const Plant& last = plants.back();
    for (int d = 1; d <= options.blend_frames; ++d) {
      const double w = 1.0 - static_cast<double>(d) / (options.blend_frames + 1);
      if (const int t = first.begin - d; t >= 0) targets[k][t] = {w, was(t) + w * (first.pin - was(first.begin))};
      if (const int t = last.end - 1 + d; t < frames) targets[k][t] = {w, was(t) + w * (last.pin - was(last.end - 1))};
    }
    ++report.feet;
    report.plants += static_cast<int>(plants.size());
  }
  report.max_miss = detail::reach_targets(skeleton, motion, legs, targets, positions, size);
  return report;
}

}  // namespace nec
