// Speed and turn limits (motion_limits.h): gait timing per body plan, the
// fastest gait and sharpest turn a rig's legs allow, typical speeds, the spec
// clamped to them, and the public speed queries of motion_synthesis.h.
#include "nec/zoo/motion_synthesis.h"

#include "motion_limits.h"

#include <algorithm>
#include <cmath>

namespace nec::zoo {
namespace detail {

constexpr double kMinSwingSeconds = 0.1;  // shortest swing the cadence may demand (3 frames at 30 fps)

GaitTuning gait_tuning(BodyPlan plan, Action action) {
  const bool trot = action == Action::Trot;
  const bool fast = action == Action::Run || action == Action::Gallop;
  if (plan == BodyPlan::Hopper) return fast ? GaitTuning{4.0, 2.0, 0.25} : GaitTuning{1.6, 1.4, 0.2};  // hops
  switch (moves_like(plan)) {
    case BodyPlan::Quadruped:
      return trot ? GaitTuning{2.6, 1.5, 0.15} : fast ? GaitTuning{5.0, 2.0, 0.2} : GaitTuning{1.3, 0.9, 0.12};
    case BodyPlan::Dragon:
      return trot ? GaitTuning{2.0, 1.1, 0.15} : fast ? GaitTuning{3.8, 1.5, 0.2} : GaitTuning{1.0, 0.7, 0.12};
    case BodyPlan::Hexapod:
      return fast ? GaitTuning{5.0, 3.5, 0.22} : GaitTuning{2.2, 2.0, 0.2};
    case BodyPlan::Spider:
      return fast ? GaitTuning{4.5, 3.0, 0.25} : GaitTuning{1.8, 1.6, 0.2};
    case BodyPlan::Centipede:
      return fast ? GaitTuning{3.5, 2.6, 0.3} : GaitTuning{1.8, 1.6, 0.25};
    case BodyPlan::Bird:
      return fast ? GaitTuning{4.5, 2.3, 0.2} : GaitTuning{1.8, 1.5, 0.15};
    default:
      return fast ? GaitTuning{4.0, 1.4, 0.2} : GaitTuning{1.5, 0.95, 0.12};
  }
}

double max_gait_frequency(double duty_factor) { return (1.0 - duty_factor) / kMinSwingSeconds; }

namespace {

// Body-length speeds of the non-gait actions.
double typical_body_speed(Action action) {
  switch (action) {
    case Action::Slither: return 0.25;
    case Action::Swim: return 0.8;
    case Action::Fly:
    case Action::Glide: return 2.5;
    case Action::TakeOff: return 1.5;
    default: return 0.0;
  }
}

// Fastest a gait can go (body lengths per second): the legs' stance travel at the highest cadence.
double gait_speed_limit(const Creature& creature, const Rig& rig, Action action) {
  if (!has_usable_legs(rig)) return 0.0;
  const GaitPattern gait = gait_pattern(creature, action);
  const double frequency = std::min(max_gait_frequency(gait.duty_factor), 2.5 * gait_tuning(creature.plan, action).frequency);
  return rig.max_stance_travel * frequency / gait.duty_factor / rig.body_length;
}

double typical_speed(const Creature& creature, const Rig& rig, Action action) {
  if (is_gait(action)) {
    if (action == Action::Turn) return 0.0;
    // The plan's usual speed, kept well inside what its legs can do.
    const double usual = gait_tuning(creature.plan, action).leg_speed * rig.leg_reach / rig.body_length;
    return std::min(usual, 0.55 * gait_speed_limit(creature, rig, action));
  }
  if (action == Action::Jump) return 1.2 * rig.leg_reach / rig.body_length;
  return typical_body_speed(action);
}

double max_speed(const Creature& creature, const Rig& rig, Action action) {
  const double typical = typical_speed(creature, rig, action);
  if (is_gait(action)) {
    if (action == Action::Turn) return 0.0;
    return std::min(gait_speed_limit(creature, rig, action), 2.5 * typical);
  }
  if (action == Action::Jump) return 2.5 * typical;
  return 3.0 * typical;
}

double max_turn_rate(const Creature& creature, const Rig& rig, Action action, double speed) {
  if (!is_gait(action)) return action == Action::Slither ? 60.0 : 120.0;
  if (!has_usable_legs(rig) || rig.foot_radius <= 0.0) return 0.0;
  const GaitPattern gait = gait_pattern(creature, action);
  const GaitTuning tuning = gait_tuning(creature.plan, action == Action::Turn ? Action::Walk : action);
  const double frequency = std::min(max_gait_frequency(gait.duty_factor), 2.5 * tuning.frequency);
  // Foot speed from turning: omega * radius; travel per stance = (v + omega r) * duty / f.
  const double room = rig.max_stance_travel * frequency / gait.duty_factor - speed * rig.body_length;
  return std::clamp(room / rig.foot_radius * 180.0 / kPi, 0.0, 180.0);
}

}  // namespace

// The spec as it will be made.
MotionSpec effective_spec(const Creature& creature, const Rig& rig, const MotionSpec& requested) {
  MotionSpec spec = requested;
  const Action action = spec.action;
  const double typical = typical_speed(creature, rig, action);
  const double most = max_speed(creature, rig, action);
  if (!is_locomotion(action)) {
    spec.turn_rate = 0.0;
    spec.start_from_still = false;
    spec.stop_at_end = false;
  }
  switch (action) {
    case Action::Turn:
      spec.speed = 0.0;
      if (std::abs(spec.turn_rate) < 15.0) spec.turn_rate = spec.turn_rate < 0.0 ? -60.0 : 60.0;
      break;
    case Action::Jump:
      spec.speed = std::clamp(spec.speed, 0.0, most);
      break;
    case Action::TakeOff:
      spec.speed = std::clamp(spec.speed, 0.5 * typical, 2.0 * typical);
      break;
    case Action::Fly:
    case Action::Glide:
      spec.start_from_still = false;
      spec.stop_at_end = false;
      spec.speed = std::clamp(spec.speed, 0.4 * typical, most);
      break;
    default:
      if (is_locomotion(action)) {
        spec.speed = std::clamp(spec.speed, 0.3 * typical, std::max(most, 0.3 * typical));
      } else {
        spec.speed = 0.0;
      }
      break;
  }
  if (action != Action::Walk && action != Action::Run) spec.direction = 0.0;
  if (!takes_manner(action)) spec.manner = Manner::Neutral;
  if (spec.direction != 0.0) {
    // Backing up and moving sideways go straight, below the typical pace of the gait.
    spec.turn_rate = 0.0;
    spec.speed = std::min(spec.speed, 0.8 * typical);
  }
  if (is_locomotion(action)) {
    const double turn_limit = max_turn_rate(creature, rig, action, spec.speed);
    spec.turn_rate = std::clamp(spec.turn_rate, -turn_limit, turn_limit);
  }
  if (action == Action::Attack || action == Action::Point || action == Action::Kick) {
    if (spec.side == Side::None) spec.side = (mix_seed(spec.seed, 0xA77AC) & 1) ? Side::Left : Side::Right;
  } else if (action != Action::Wave && action != Action::RaiseHands) {
    spec.side = Side::None;
  }
  return spec;
}

}  // namespace detail

double typical_speed(const Creature& creature, Action action) {
  return detail::typical_speed(creature, detail::analyze(creature), action);
}

double max_speed(const Creature& creature, Action action) {
  return detail::max_speed(creature, detail::analyze(creature), action);
}

double max_turn_rate(const Creature& creature, Action action, double speed) {
  return detail::max_turn_rate(creature, detail::analyze(creature), action, speed);
}

}  // namespace nec::zoo
