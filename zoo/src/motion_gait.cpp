// Actions, which body plans support them, motion spec checks, travel ramps
// and the gait phase patterns of every body plan.
#include "nec/zoo/motion_synthesis.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nec::zoo {
namespace {

struct ActionName {
  Action action;
  std::string_view name;
};

constexpr ActionName kActionNames[] = {
    {Action::Idle, "idle"},       {Action::Walk, "walk"},       {Action::Trot, "trot"},
    {Action::Run, "run"},         {Action::Gallop, "gallop"},   {Action::Turn, "turn"},
    {Action::Jump, "jump"},       {Action::Sit, "sit"},         {Action::LieDown, "lie_down"},
    {Action::Attack, "attack"},   {Action::Slither, "slither"}, {Action::Swim, "swim"},
    {Action::Fly, "fly"},         {Action::Glide, "glide"},     {Action::TakeOff, "take_off"},
    {Action::FlapWings, "flap_wings"}, {Action::Wave, "wave"},     {Action::RaiseHands, "raise_hands"},
    {Action::Point, "point"},     {Action::Clap, "clap"},       {Action::Bow, "bow"},
    {Action::Crouch, "crouch"},   {Action::Kick, "kick"},       {Action::Eat, "eat"},
    {Action::Shake, "shake"},     {Action::JumpingJacks, "jumping_jacks"}, {Action::Stretch, "stretch"},
    {Action::Dance, "dance"},     {Action::GetUp, "get_up"},
};

double fraction(double x) { return x - std::floor(x); }

double smoothstep01(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// Still time before a start / after a stop, and the ramp length, for a clip of `seconds`.
double still_seconds(double seconds) { return std::min(0.5, 0.12 * seconds); }
double ramp_seconds(double seconds) { return std::min(1.0, 0.25 * seconds); }

}  // namespace

std::string_view action_name(Action action) {
  for (const ActionName& entry : kActionNames) {
    if (entry.action == action) return entry.name;
  }
  return "unknown";
}

bool parse_action(std::string_view name, Action& action) {
  for (const ActionName& entry : kActionNames) {
    if (entry.name == name) {
      action = entry.action;
      return true;
    }
  }
  return false;
}

bool is_locomotion(Action action) {
  switch (action) {
    case Action::Walk:
    case Action::Trot:
    case Action::Run:
    case Action::Gallop:
    case Action::Turn:
    case Action::Slither:
    case Action::Swim:
    case Action::Fly:
    case Action::Glide:
      return true;
    default:
      return false;
  }
}

bool is_gait(Action action) {
  return action == Action::Walk || action == Action::Trot || action == Action::Run || action == Action::Gallop ||
         action == Action::Turn;
}

namespace {

std::vector<Action> listed_actions(BodyPlan plan) {
  using A = Action;
  switch (plan) {
    case BodyPlan::Biped:
      return {A::Idle, A::Walk,       A::Run,   A::Turn, A::Jump, A::Sit,    A::Attack,       A::Wave,
              A::RaiseHands, A::Point, A::Clap, A::Bow, A::Crouch, A::Kick, A::JumpingJacks, A::Stretch, A::Dance};
    case BodyPlan::Quadruped:
      return {A::Idle, A::Walk, A::Trot, A::Gallop, A::Turn, A::Jump, A::Sit, A::LieDown, A::Attack, A::Eat, A::Shake};
    case BodyPlan::Hexapod:
    case BodyPlan::Spider:
      return {A::Idle, A::Walk, A::Run, A::Turn, A::Jump, A::LieDown, A::Attack};
    case BodyPlan::Snake:
      return {A::Idle, A::Attack, A::Slither};
    case BodyPlan::Bird:
      return {A::Idle, A::Walk, A::Run, A::Jump, A::Sit, A::Attack, A::Fly, A::Glide, A::TakeOff, A::FlapWings, A::Shake};
    case BodyPlan::Fish:
      return {A::Idle, A::Attack, A::Swim};
    case BodyPlan::Dragon:
      return {A::Idle, A::Walk,   A::Trot, A::Gallop, A::Turn,    A::Sit,
              A::LieDown, A::Attack, A::Fly, A::Glide, A::TakeOff, A::FlapWings, A::Eat, A::Shake};
    case BodyPlan::Centipede:
      return {A::Idle, A::Walk, A::Run, A::Attack};
    case BodyPlan::Crab:
      return {A::Idle, A::Walk, A::Run, A::Turn, A::LieDown, A::Attack};
    case BodyPlan::Ungulate:
      return {A::Idle, A::Walk, A::Trot, A::Gallop, A::Turn, A::Jump, A::LieDown, A::Eat, A::Shake};
    case BodyPlan::Elephant:
      return {A::Idle, A::Walk, A::Trot, A::Turn, A::LieDown, A::Attack};
    case BodyPlan::GroundBird:
      return {A::Idle, A::Walk, A::Run, A::Jump, A::Sit, A::Attack, A::FlapWings, A::Shake};
    case BodyPlan::Hopper:
      return {A::Idle, A::Walk, A::Run, A::Jump, A::Sit};
    case BodyPlan::Dinosaur:
      return {A::Idle, A::Walk, A::Run, A::Sit, A::Attack};
    case BodyPlan::Primate:
      return {A::Idle, A::Walk, A::Gallop, A::Turn, A::Sit, A::Attack};
  }
  return {A::Idle};
}

}  // namespace

std::vector<Action> supported_actions(BodyPlan plan) {
  std::vector<Action> actions = listed_actions(plan);
  const auto has = [&](Action a) { return std::find(actions.begin(), actions.end(), a) != actions.end(); };
  if (has(Action::Sit) || has(Action::LieDown)) actions.push_back(Action::GetUp);
  return actions;
}

Action lowering_action(BodyPlan plan) { return supports_action(plan, Action::LieDown) ? Action::LieDown : Action::Sit; }

std::string_view manner_name(Manner manner) {
  switch (manner) {
    case Manner::Neutral: return "neutral";
    case Manner::Tired: return "tired";
    case Manner::Energetic: return "energetic";
    case Manner::Cautious: return "cautious";
    case Manner::Proud: return "proud";
  }
  return "neutral";
}

bool parse_manner(std::string_view name, Manner& manner) {
  for (Manner m : kAllManners) {
    if (manner_name(m) == name) {
      manner = m;
      return true;
    }
  }
  return false;
}

bool takes_manner(Action action) { return is_gait(action) || action == Action::Idle; }

bool supports_action(BodyPlan plan, Action action) {
  const std::vector<Action> actions = supported_actions(plan);
  return std::find(actions.begin(), actions.end(), action) != actions.end();
}

void MotionSpec::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("MotionSpec: " + what); };
  if (!(seconds > 0.0) || seconds > 600.0) fail("seconds must be in (0, 600], got " + std::to_string(seconds));
  if (!(fps >= 1.0) || fps > 1000.0) fail("fps must be in [1, 1000], got " + std::to_string(fps));
  if (!std::isfinite(speed) || speed < 0.0) fail("speed must be finite and >= 0, got " + std::to_string(speed));
  if (!std::isfinite(turn_rate) || std::abs(turn_rate) > 720.0) {
    fail("turn_rate must be within +-720 degrees per second, got " + std::to_string(turn_rate));
  }
  if (static_cast<int>(seconds * fps) < 2) fail("the clip must have at least 2 frames");
  if (!std::isfinite(direction) || std::abs(direction) > 180.0) {
    fail("direction must be within +-180 degrees, got " + std::to_string(direction));
  }
}

SpeedClass classify_speed(double speed, double typical) {
  if (typical <= 0.0) return SpeedClass::Normal;
  if (speed < kSlowSpeedRatio * typical) return SpeedClass::Slow;
  if (speed > kFastSpeedRatio * typical) return SpeedClass::Fast;
  return SpeedClass::Normal;
}

double travel_ramp(const MotionSpec& spec, double t) {
  if (!is_locomotion(spec.action)) return 0.0;
  const double still = still_seconds(spec.seconds);
  const double ramp = ramp_seconds(spec.seconds);
  double share = 1.0;
  if (spec.start_from_still) share *= smoothstep01((t - still) / ramp);
  if (spec.stop_at_end) share *= smoothstep01((spec.seconds - still - t) / ramp);
  return share;
}

double heading_change_degrees(const MotionSpec& spec) {
  if (!is_locomotion(spec.action)) return 0.0;
  // The integral of a smoothstep ramp over its length is half the length.
  const double still = still_seconds(spec.seconds);
  const double ramp = ramp_seconds(spec.seconds);
  double moving = spec.seconds;
  if (spec.start_from_still) moving -= still + 0.5 * ramp;
  if (spec.stop_at_end) moving -= still + 0.5 * ramp;
  return spec.turn_rate * std::max(0.0, moving);
}

GaitPattern gait_pattern(const Creature& creature, Action action) {
  GaitPattern gait;
  if (!is_gait(action)) return gait;
  std::vector<const Limb*> legs;
  for (const Limb& limb : creature.limbs) {
    if (limb.kind == LimbKind::Leg) legs.push_back(&limb);
  }
  int pairs = 0;
  for (const Limb* leg : legs) pairs = std::max(pairs, leg->pair + 1);
  const bool fast = action == Action::Run || action == Action::Gallop;
  const BodyPlan plan = moves_like(creature.plan);
  if (creature.plan == BodyPlan::Hopper) {  // both feet together, a flight between hops
    gait.phases.assign(legs.size(), 0.0);
    gait.duty_factor = fast ? 0.3 : 0.45;
    return gait;
  }
  for (const Limb* leg : legs) {
    const bool right = leg->side == Side::Right;
    const double contralateral = right ? 0.5 : 0.0;
    double phase = 0.0;
    switch (plan) {
      case BodyPlan::Quadruped:
      case BodyPlan::Dragon:
        if (action == Action::Trot) {
          phase = fraction(0.5 * leg->pair + contralateral);  // diagonal pairs together
        } else if (action == Action::Gallop) {
          // Transverse gallop: hind left, hind right, then fore left, fore right
          // (a smaller phase offset touches down later).
          const bool front = leg->pair == 0;
          phase = fraction(-(front ? 0.5 : 0.0) - (right ? 0.1 : 0.0));
        } else {
          // Lateral-sequence walk: LH, LF, RH, RF touch down a quarter cycle apart.
          const bool front = leg->pair == 0;
          phase = fraction((front ? -0.25 : 0.0) + contralateral);
        }
        break;
      case BodyPlan::Hexapod:
        phase = fraction(0.5 * leg->pair + contralateral);  // tripods L1 R2 L3 / R1 L2 R3
        break;
      case BodyPlan::Spider:
      case BodyPlan::Centipede: {
        // Wave from back to front: each leg steps a fixed lag after the one behind it.
        const double lag = plan == BodyPlan::Spider ? 1.0 / std::max(pairs, 1)
                                                              : std::min(1.0 / std::max(pairs, 1), 0.125);
        phase = fraction(-(pairs - 1 - leg->pair) * lag + contralateral);
        break;
      }
      default:
        phase = fraction(0.5 * leg->pair + contralateral);  // bipeds and birds alternate
        break;
    }
    gait.phases.push_back(phase);
  }
  switch (plan) {
    case BodyPlan::Quadruped:
    case BodyPlan::Dragon:
      gait.duty_factor = action == Action::Trot ? 0.5 : action == Action::Gallop ? 0.3 : 0.7;
      break;
    case BodyPlan::Hexapod:
      gait.duty_factor = fast ? 0.5 : 0.6;
      break;
    case BodyPlan::Spider:
      gait.duty_factor = fast ? 0.6 : 0.75;
      break;
    case BodyPlan::Centipede:
      gait.duty_factor = fast ? 0.55 : 0.65;
      break;
    default:
      gait.duty_factor = fast ? 0.38 : 0.62;
      break;
  }
  return gait;
}

}  // namespace nec::zoo
