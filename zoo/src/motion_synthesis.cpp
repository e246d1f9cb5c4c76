// The public entry point (synthesize_motion) and the Synthesizer's timeline:
// gait frequency and style drawn from the seed, the root trajectory
// integrated from speed and turn rate, and the steps run into the output clip.
#include "nec/zoo/motion_synthesis.h"

#include "synthesizer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nec::zoo {
namespace detail {

Synthesizer::Synthesizer(const Creature& creature, const Rig& rig, const MotionSpec& spec)
    : creature_(creature), motion_plan_(moves_like(creature.plan)), skeleton_(creature.skeleton), rig_(rig), spec_(spec), style_(mix_seed(spec.seed, 0x5EED)) {
  joint_count_ = skeleton_.joint_count();
  fps_ = spec_.fps;
  frames_ = std::max(2, static_cast<int>(std::lround(spec_.seconds * spec_.fps)));
  reach_ = rig_.leg_reach > 0.0 ? rig_.leg_reach : 0.3 * rig_.body_length;
  gait_ = gait_pattern(creature_, spec_.action);
  if (is_gait(spec_.action) && has_usable_legs(rig_)) {
    tuning_ = gait_tuning(creature_.plan, spec_.action == Action::Turn ? Action::Walk : spec_.action);
    const double typical = tuning_.leg_speed * rig_.leg_reach;
    const double v = length_speed();
    const double f_max = std::min(max_gait_frequency(gait_.duty_factor), 2.5 * tuning_.frequency);
    double f = typical > 0.0 && v > 0.0 ? tuning_.frequency * std::sqrt(v / typical) : tuning_.frequency;
    const double foot_speed = v + std::abs(radians(spec_.turn_rate)) * rig_.foot_radius;
    if (rig_.max_stance_travel > 0.0) f = std::max(f, foot_speed * gait_.duty_factor / rig_.max_stance_travel);
    frequency_ = std::clamp(f, 0.3 * tuning_.frequency, f_max);
  }
  const double cycle = frequency_ > 0.0 ? 1.0 / frequency_ : 0.0;
  pad_ = static_cast<int>(std::ceil(std::max(1.5, 1.5 * cycle) * fps_));
  total_ = frames_ + 2 * pad_;

  breath_rate_ = style_.uniform(0.22, 0.36);
  breath_phase_ = style_.uniform(0.0, 2.0 * kPi);
  look_phase_ = style_.uniform(0.0, 2.0 * kPi);
  look_amount_ = style_.uniform(0.2, 0.45);
  sway_phase_ = style_.uniform(0.0, 2.0 * kPi);
  step_scale_ = style_.uniform(0.85, 1.15);
  tail_scale_ = style_.uniform(0.8, 1.2);

  switch (spec_.manner) {
    case Manner::Tired:
      manner_ = {-radians(8.0), -radians(18.0), 0.5, 0.7, 0.04, 0.0};
      breath_rate_ *= 1.6;
      look_amount_ *= 0.5;
      break;
    case Manner::Energetic:
      manner_ = {-radians(2.0), radians(5.0), 1.5, 1.35, 0.0, 0.025};
      breath_rate_ *= 1.3;
      break;
    case Manner::Cautious:
      manner_ = {-radians(10.0), -radians(8.0), 0.6, 0.8, 0.1, 0.0};
      look_amount_ *= 2.0;
      break;
    case Manner::Proud:
      manner_ = {radians(6.0), radians(12.0), 1.1, 1.1, -0.02, 0.0};
      look_amount_ *= 0.7;
      break;
    case Manner::Neutral:
      break;
  }
  step_scale_ *= manner_.step;

  if (is_gait(spec_.action)) {
    const double still = std::min(0.5, 0.12 * spec_.seconds);
    if (spec_.start_from_still) move_begin_ = still;
    if (spec_.stop_at_end && frequency_ > 0.0) {
      move_end_ = spec_.seconds - still - 0.5 * (1.0 - gait_.duty_factor) / frequency_;
    }
  }
}

double Synthesizer::gait_share(double t) const {
  if (!is_gait(spec_.action)) return 0.0;
  return is_locomotion(spec_.action) ? travel_ramp(spec_, t) : 0.0;
}

// Root trajectory: speed and turn rate integrated from t = 0 both ways.
void Synthesizer::plan_travel() {
  heading_.assign(total_, 0.0);
  speed_.assign(total_, 0.0);
  turn_.assign(total_, 0.0);
  travelled_.assign(total_, 0.0);
  root_.assign(total_, Vec3::Zero());
  const double v = length_speed();
  const double T = spec_.seconds;
  const double k = std::min(1.0, T / 3.0);
  for (int f = 0; f < total_; ++f) {
    const double t = time(f);
    double speed = 0.0;
    double turn = 0.0;
    switch (spec_.action) {
      case Action::Jump:
        speed = v * pulse(t, event_b_, event_b_ + 0.15 * k, event_c_ - 0.1 * k, event_c_);  // push-off to landing
        break;
      case Action::TakeOff:
        speed = v * ramp_between(t, event_b_ - 0.1, event_b_ + 1.2 * k);
        break;
      case Action::Attack:
        if (motion_plan_ == BodyPlan::Fish) {
          const double burst = pulse(t, event_b_, event_b_ + 0.1, event_c_, event_c_ + 0.5 * k);
          speed = rig_.body_length * (0.1 + 2.4 * burst);
        }
        break;
      case Action::Idle:
        if (motion_plan_ == BodyPlan::Fish) speed = 0.03 * rig_.body_length;
        break;
      default:
        if (is_locomotion(spec_.action)) {
          const double share = travel_ramp(spec_, t);
          speed = v * share;
          turn = radians(spec_.turn_rate) * share;
        }
        break;
    }
    speed_[f] = speed;
    turn_[f] = turn;
  }
  const double dt = 1.0 / fps_;
  const double offset = radians(spec_.direction);  // travel relative to the facing (backing up, sidestepping)
  for (int f = pad_ + 1; f < total_; ++f) {
    heading_[f] = heading_[f - 1] + 0.5 * (turn_[f - 1] + turn_[f]) * dt;
    const double step = 0.5 * (speed_[f - 1] + speed_[f]) * dt;
    const double mid = 0.5 * (heading_[f - 1] + heading_[f]) + offset;
    travelled_[f] = travelled_[f - 1] + step;
    root_[f] = root_[f - 1] + Vec3(std::sin(mid), 0.0, std::cos(mid)) * step;
  }
  for (int f = pad_ - 1; f >= 0; --f) {
    heading_[f] = heading_[f + 1] - 0.5 * (turn_[f + 1] + turn_[f]) * dt;
    const double step = 0.5 * (speed_[f + 1] + speed_[f]) * dt;
    const double mid = 0.5 * (heading_[f + 1] + heading_[f]) + offset;
    travelled_[f] = travelled_[f + 1] - step;
    root_[f] = root_[f + 1] - Vec3(std::sin(mid), 0.0, std::cos(mid)) * step;
  }
}

SynthesizedMotion Synthesizer::run() {
  plan_body();
  plan_legs();
  adjust_height();
  solve_legs();

  SynthesizedMotion out;
  out.spec = spec_;
  out.gait = gait_;
  out.gait_frequency = frequency_;
  Motion& motion = out.motion;
  motion = Motion::rest(skeleton_, frames_, fps_);
  for (int t = 0; t < frames_; ++t) {
    const int f = t + pad_;
    for (int j = 0; j < joint_count_; ++j) motion.rotation(t, j) = local_[at(f, j)];
    motion.translation(t, 0) = root_[f];
  }
  for (size_t i = 0; i < rig_.legs.size(); ++i) {
    LegTrack track;
    track.limb = rig_.legs[i].limb;
    track.stance.assign(frames_, rig_.legs[i].usable ? 1 : 0);
    if (rig_.legs[i].usable) {
      for (int t = 0; t < frames_; ++t) track.stance[t] = stance_[i][t + pad_];
    }
    out.legs.push_back(std::move(track));
  }
  return out;
}

}  // namespace detail

SynthesizedMotion synthesize_motion(const Creature& creature, const MotionSpec& spec) {
  spec.validate();
  if (!supports_action(creature.plan, spec.action)) {
    throw std::invalid_argument("synthesize_motion: a " + std::string(body_plan_name(creature.plan)) + " cannot " +
                                std::string(action_name(spec.action)));
  }
  creature.skeleton.validate();
  if (spec.action == Action::GetUp) {
    // Lying down (or sitting down) played backwards: every pose and foot contact in reverse order.
    MotionSpec lowering = spec;
    lowering.action = lowering_action(creature.plan);
    SynthesizedMotion made = synthesize_motion(creature, lowering);
    Motion& m = made.motion;
    for (int t = 0, u = m.frame_count - 1; t < u; ++t, --u) {
      for (int j = 0; j < m.joint_count; ++j) {
        std::swap(m.rotation(t, j), m.rotation(u, j));
        std::swap(m.translation(t, j), m.translation(u, j));
      }
    }
    for (LegTrack& leg : made.legs) std::reverse(leg.stance.begin(), leg.stance.end());
    made.spec.action = Action::GetUp;
    return made;
  }
  const detail::Rig rig = detail::analyze(creature);
  const MotionSpec effective = detail::effective_spec(creature, rig, spec);
  detail::Synthesizer synthesizer(creature, rig, effective);
  return synthesizer.run();
}

}  // namespace nec::zoo
