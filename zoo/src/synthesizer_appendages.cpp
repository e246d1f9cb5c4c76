// Limbs that do not stand: fins, antennae, jaws and trunks; the frame's forward
// kinematics with the arms aimed in the chest's frame; wings folded, spread
// or beating for flight (Synthesizer::pose_appendages, assemble_frame, pose_wing).
#include "synthesizer.h"

#include <algorithm>
#include <cmath>

namespace nec::zoo::detail {

// Fins, antennae, jaws and trunks: local rotations.
void Synthesizer::pose_appendages(int f, double t) {
  const Action action = spec_.action;
  const double share = gait_share(t);
  // Fins: sculling pectorals, swaying median fins.
  for (const Appendage& fin : rig_.fins) {
    const std::vector<int>& joints = fin.limb->joints;
    const double rate = action == Action::Idle ? 0.8 : 1.6;
    if (fin.limb->side == Side::None) {
      const double sway = radians(8.0) * std::sin(2.0 * kPi * rate * t);
      for (size_t k = 0; k < joints.size(); ++k) local_[at(f, joints[k])] = yaw_rotation(sway / joints.size());
    } else {
      const double beat = std::sin(2.0 * kPi * rate * t + (fin.limb->side == Side::Right ? kPi : 0.0) * 0.0);
      const double tuck = action == Action::Swim || action == Action::Attack ? radians(30.0) : radians(5.0);
      local_[at(f, joints[0])] =
          (axis_angle(fin.sweep_axis, tuck + radians(10.0) * std::cos(2.0 * kPi * rate * t)) *
           axis_angle(fin.lift_axis, radians(15.0) * beat))
              .normalized();
    }
  }
  // Antennae: lagged sway.
  for (const Limb* antenna : rig_.antennae) {
    for (size_t k = 0; k < antenna->joints.size(); ++k) {
      const double phase = 2.0 * kPi * 0.7 * t - 0.6 * k + sway_phase_ + (antenna->side == Side::Right ? 1.3 : 0.0);
      local_[at(f, antenna->joints[k])] =
          (yaw_rotation(radians(6.0) * std::sin(phase)) * axis_angle(Vec3::UnitX(), radians(5.0) * std::cos(phase * 0.7)))
              .normalized();
    }
  }
  // Trunks: a slow swing passed down the chain; curled up in an attack (trumpeting).
  for (const Limb* trunk : rig_.trunks) {
    const double raise = action == Action::Attack ? pulse(t, event_a_ - 0.3, event_b_, event_d_, event_d_ + 0.4) : 0.0;
    const double count = static_cast<double>(trunk->joints.size());
    for (size_t k = 0; k < trunk->joints.size(); ++k) {
      const double phase = 2.0 * kPi * 0.4 * t - 0.5 * k + sway_phase_;
      local_[at(f, trunk->joints[k])] =
          (yaw_rotation(radians(8.0) * std::sin(phase)) *
           axis_angle(Vec3::UnitX(), radians(4.0) * std::cos(phase) - radians(120.0) / count * raise))
              .normalized();
    }
  }
  // Jaws: open for attacks, a little while breathing hard.
  for (const Limb* jaw : rig_.jaws) {
    double open = 0.0;
    if (action == Action::Attack) open = radians(30.0) * pulse(t, event_a_ + 0.15, event_b_, event_b_ + 0.05, event_b_ + 0.15);
    if (action == Action::Gallop || action == Action::Run) open = radians(6.0) * share;
    if (action == Action::Eat) {  // chewing
      open = radians(8.0) * (0.5 + 0.5 * std::sin(2.0 * kPi * 2.2 * t)) * pulse(t, event_b_, event_b_ + 0.2, event_c_ - 0.2, event_c_);
    }
    const Quat q = axis_angle(Vec3::UnitX(), open);
    if (!jaw->joints.empty()) local_[at(f, jaw->joints[0])] = q;
  }
}

// Where a gesture puts an arm: upper arm and forearm directions in the chest's heading frame (x to the
// creature's left, y up, z forward), and how far the arm is in the gesture (0: the ordinary pose).
Synthesizer::ArmGesture Synthesizer::arm_gesture(const Appendage& arm, int f, double t) const {
  const Action action = spec_.action;
  const bool both = spec_.side == Side::None;
  const bool this_arm = both || arm.limb->side == spec_.side;
  const double side = side_sign(arm.limb->side);
  ArmGesture g;
  const double in_gesture = pulse(t, event_a_, event_b_, event_c_, event_d_);
  const auto mirrored = [side](double x, double y, double z) { return Vec3(side * x, y, z).normalized(); };
  switch (action) {
    case Action::Wave: {
      if (!this_arm) break;
      // The forearm swings about the forward axis, twice a second, around an upright hand.
      const double swing = radians(12.0) + radians(28.0) * std::sin(2.0 * kPi * 2.0 * (t - event_b_));
      g = {in_gesture, mirrored(0.75, 0.55, 0.2), mirrored(std::sin(swing), std::cos(swing), 0.15)};
      break;
    }
    case Action::RaiseHands:
      if (this_arm) g = {in_gesture, mirrored(0.3, 1.0, 0.1), mirrored(0.15, 1.0, 0.05)};
      break;
    case Action::Point:
      if (this_arm) g = {in_gesture, mirrored(0.15, 0.05, 1.0), mirrored(0.05, 0.05, 1.0)};
      break;
    case Action::Clap: {
      // Hands meet in front of the chest and part again, about two claps a second: the forearm turns in by what
      // brings the wrist to the midline, whatever the shoulders' width and the arm's proportions.
      const double apart = 0.5 - 0.5 * std::cos(2.0 * kPi * 2.2 * std::max(0.0, t - event_b_));
      const Vec3 upper = mirrored(0.25, -0.35, 0.9);
      if (arm.lengths.size() < 2) break;
      const int pivot = arm.limb->joints[arm.pivot];
      const int chest = skeleton_.parents[arm.limb->joints.front()];
      const Quat heading = yaw_rotation(heading_angle(global_[at(f, chest)]));
      const Vec3 from_midline = heading.conjugate() * (position_[at(f, pivot)] - position_[at(f, chest)]);
      const double elbow_x = from_midline.x() + upper.x() * arm.lengths[0];
      const double inward = std::clamp(-elbow_x / arm.lengths[1], -0.95, 0.95) * (1.0 - apart);
      const double x = inward + side * 0.1 * apart;
      g = {in_gesture, upper, Vec3(x, 0.2, std::sqrt(std::max(0.05, 1.0 - x * x - 0.04))).normalized()};
      break;
    }
    case Action::Kick:
      // Out to the sides for balance.
      g = {in_gesture, mirrored(0.6, -0.75, 0.15), mirrored(0.55, -0.45, 0.45)};
      break;
    case Action::JumpingJacks: {
      // Up over the head through the side: out at half way, overhead with the feet apart.
      const double end = event_a_ + jack_count() * kJackSeconds;
      const double angle = kPi * jack_phase(t).spread;  // from down (0) through the side to up
      const Vec3 direction = mirrored(std::sin(angle), -std::cos(angle), 0.05);
      g = {pulse(t, event_a_ - 0.2, event_a_, end, end + 0.2), direction, direction};
      break;
    }
    case Action::Stretch:
      g = {in_gesture, mirrored(0.15, 1.0, 0.05), mirrored(0.08, 1.0, 0.0)};
      break;
    case Action::Dance: {
      // Each arm swings up in front on its own beat, bent at the elbow.
      const double dancing = pulse(t, event_a_, event_a_ + 0.3, event_d_ - 0.3, event_d_);
      const double lift = 0.5 + 0.5 * std::sin(kPi * kDanceBeat * (t - event_a_) + side * 0.5 * kPi);
      g = {dancing, mirrored(0.45, -0.2 + 0.9 * lift, 0.6), mirrored(0.1, 0.5 + 0.5 * lift, 0.7)};
      break;
    }
    default:
      break;
  }
  return g;
}

// Converts the midline's global targets (in local_) into locals top-down,
// adds arms, and runs forward kinematics for the frame.
void Synthesizer::assemble_frame(int f) {
  const Midline& m = rig_.midline;
  const std::vector<int>& parents = skeleton_.parents;
  for (int j = 0; j < joint_count_; ++j) {
    const int p = parents[j];
    const Quat parent_global = p >= 0 ? global_[at(f, p)] : Quat::Identity();
    if (m.member[j]) {
      const Quat target = local_[at(f, j)];
      local_[at(f, j)] = (parent_global.conjugate() * target).normalized();
    }
    global_[at(f, j)] = (parent_global * local_[at(f, j)]).normalized();
    position_[at(f, j)] = p >= 0 ? Vec3(position_[at(f, p)] + parent_global * skeleton_.offsets[j]) : root_[f];
  }

  // Arms: directions in the chest's heading frame, then aimed; wings after them.
  const double t = time(f);
  const double share = gait_share(t);
  const double clock = gait_clock(t);
  const Action action = spec_.action;
  for (const Appendage& arm : rig_.arms) {
    const std::vector<int>& joints = arm.limb->joints;
    const int pivot = joints[arm.pivot];
    const int parent = parents[pivot];
    const double side = side_sign(arm.limb->side);
    // Swing opposite to the same-side leg: forward while that leg is behind.
    double same_side_phase = 0.0;
    for (size_t i = 0; i < rig_.legs.size() && i < gait_.phases.size(); ++i) {
      if (rig_.legs[i].side == arm.limb->side) same_side_phase = gait_.phases[i];
    }
    const bool running = action == Action::Run;
    double swing = -radians(running ? 35.0 : 18.0) * manner_.arm_swing * share *
                   std::cos(2.0 * kPi * (clock + same_side_phase));
    double elbow = radians(running ? 85.0 : 20.0) * share + radians(10.0) * (1.0 - share);
    double raise = 0.0;  // sideways, away from the body
    if (action == Action::Sit || action == Action::Crouch) {
      const double w = ramp_between(t, event_a_, event_b_);
      swing = radians(45.0) * w;
      elbow = radians(10.0) + radians(35.0) * w;
    }
    if (action == Action::Jump) {
      const double kk = std::min(1.0, spec_.seconds / 3.0);
      swing = -radians(40.0) * pulse(t, event_a_, event_b_, event_b_, event_b_ + 0.1 * kk) +
              radians(60.0) * pulse(t, event_b_, event_b_ + 0.15 * kk, event_c_ - 0.1, event_c_ + 0.2);
      elbow = radians(25.0);
    }
    if (action == Action::Attack && creature_.plan == BodyPlan::Biped) {
      const bool striking = arm.limb->side == spec_.side;
      const double windup = pulse(t, event_a_, event_b_ - 0.05, event_b_ - 0.05, event_b_);
      const double strike = pulse(t, event_b_ - 0.05, event_b_ + 0.08, event_c_, event_d_);
      const double guard = pulse(t, event_a_ - 0.3, event_a_, event_d_, event_d_ + 0.3);
      if (striking) {
        swing = radians(20.0) * guard - radians(25.0) * windup + radians(70.0) * strike;
        elbow = radians(100.0) * guard * (1.0 - strike) + radians(5.0) * strike;
      } else {
        swing = radians(40.0) * guard;
        elbow = radians(110.0) * guard;
      }
      raise = radians(5.0);
    }
    const Quat chest = yaw_rotation(heading_angle(global_[at(f, parent)]));
    const Vec3 down(side * (0.12 + std::sin(raise)), -1.0, 0.0);
    Vec3 upper = chest * (axis_angle(Vec3::UnitX(), -swing) * down.normalized());
    Vec3 lower = chest * (axis_angle(Vec3::UnitX(), -(swing + elbow)) * Vec3(side * 0.05, -1.0, 0.0).normalized());
    if (creature_.plan == BodyPlan::Crab) {
      // Claws held out in front, swaying with the steps; raised and thrust forward in an attack.
      const double threat = action == Action::Attack ? pulse(t, event_a_ - 0.3, event_b_, event_c_, event_d_) : 0.0;
      const double sway = 0.1 * share * std::sin(2.0 * kPi * (clock + same_side_phase));
      upper = chest * Vec3(side * 0.7, 0.1 + 0.9 * threat, 0.7 + sway).normalized();
      lower = chest * Vec3(-side * 0.3, 0.05 + 0.3 * threat, 1.0).normalized();
    }
    if (const ArmGesture gesture = arm_gesture(arm, f, t); gesture.weight > 0.0) {
      upper = ((1.0 - gesture.weight) * upper + gesture.weight * (chest * gesture.upper)).normalized();
      lower = ((1.0 - gesture.weight) * lower + gesture.weight * (chest * gesture.lower)).normalized();
    }
    std::vector<int> chain(joints.begin() + arm.pivot, joints.end());
    std::vector<Vec3> points(chain.size());
    points[0] = position_[at(f, pivot)];
    for (size_t k = 1; k < chain.size(); ++k) {
      const Vec3& direction = k == 1 ? upper : lower;
      points[k] = points[k - 1] + direction * arm.lengths[k - 1];
    }
    // Only the upper arm and forearm are aimed; the hand keeps its rest relation to the forearm.
    const size_t aimed = std::min<size_t>(chain.size(), 3);
    chain.resize(aimed);
    points.resize(aimed);
    aim_chain(skeleton_, chain, points, global_[at(f, parent)], &local_[at(f, 0)]);
  }
  for (const Appendage& wing : rig_.wings) pose_wing(wing, f, t);
}

// Wings: a direction per bone in the body's frame, blended between folded
// along the body and spread, beating about the body's long axis with the
// distal bones lagging; then aimed. Independent of the rest pose (a crouched
// rest may already be folded).
void Synthesizer::pose_wing(const Appendage& wing, int f, double t) {
  const std::vector<int>& joints = wing.limb->joints;
  const Action action = spec_.action;
  const double T = spec_.seconds;
  const double side = side_sign(wing.limb->side);
  const double rate = motion_plan_ == BodyPlan::Dragon ? 1.4 : 3.0;  // wing beats per second
  double open = 0.0;       // 0 folded, 1 spread
  double amplitude = 0.0;  // beat amplitude, radians
  double beat_rate = rate;
  double elevation = radians(8.0);
  switch (action) {
    case Action::Fly:
      open = 1.0;
      amplitude = radians(42.0);
      break;
    case Action::Glide:
      open = 1.0;
      elevation = radians(6.0) + radians(2.0) * std::sin(2.0 * kPi * 0.5 * t);
      break;
    case Action::TakeOff:
      open = ramp_between(t, event_a_, event_b_ - 0.1);
      amplitude = radians(50.0) * open;
      beat_rate = 1.15 * rate;
      break;
    case Action::FlapWings:
      open = pulse(t, 0.2, 0.5, T - 0.5, T - 0.2);
      amplitude = radians(45.0) * open;
      break;
    default:
      break;
  }
  const double phase = 2.0 * kPi * beat_rate * t;
  // Folded directions (left wing; x mirrored for the right): humerus back, forearm forward, the rest back.
  const Vec3 folded[3] = {Vec3(0.45, -0.15, -0.85).normalized(), Vec3(0.2, 0.0, 0.98).normalized(),
                          Vec3(0.15, -0.05, -0.99).normalized()};
  const Quat parent_global = global_[at(f, skeleton_.parents[joints[0]])];
  const Quat& body = parent_global;  // wings pitch and bank with the chest
  const size_t n = joints.size();
  std::vector<Vec3> points(n);
  points[0] = position_[at(f, joints[0])];
  auto direction = [&](size_t bone) {  // bone `bone` runs from joints[bone] to the next joint (or the end site)
    const double lag = 0.5 * static_cast<double>(bone);
    const double e = elevation + amplitude * std::sin(phase - lag);
    const double sweep = open * radians(8.0) * std::cos(phase - lag);
    // Beating wings fold a little on the upstroke, distal bones only.
    const double upstroke_fold = bone > 0 && amplitude > 0.0 ? 0.15 * open * (0.5 - 0.5 * std::sin(phase - lag)) : 0.0;
    const Vec3 spread = axis_angle(Vec3::UnitY(), side * sweep) *
                        (axis_angle(Vec3::UnitZ(), side * e) * Vec3(side, 0.0, -0.12).normalized());
    Vec3 tuck = folded[std::min<size_t>(bone, 2)];
    tuck.x() *= side;
    const double w = std::clamp(1.0 - open + upstroke_fold, 0.0, 1.0);
    return Vec3(body * ((1.0 - w) * spread + w * tuck).normalized());
  };
  for (size_t k = 1; k < n; ++k) points[k] = points[k - 1] + direction(k - 1) * skeleton_.offsets[joints[k]].norm();
  const Quat last = aim_chain(skeleton_, joints, points, parent_global, &local_[at(f, 0)]);
  // The last joint carries the wing tip's end site: aim it too.
  for (const EndSite& site : skeleton_.end_sites) {
    if (site.parent != joints[n - 1] || site.offset.norm() < 1e-12) continue;
    const Vec3 want = direction(n - 1);
    const Quat global = (Quat::FromTwoVectors(last * site.offset, want) * last).normalized();
    local_[at(f, joints[n - 1])] = (last.conjugate() * global).normalized();
    break;
  }
}

}  // namespace nec::zoo::detail
