// Legs: swing intervals from the gait phases or the action's schedule,
// footholds planted in world space, swing arcs, the root lowered or raised
// for reach, and the leg IK (two-bone or FABRIK) into local rotations.
#include "synthesizer.h"

#include <algorithm>
#include <cmath>

namespace nec::zoo::detail {

constexpr double kMaxReach = 0.985;  // the root is lowered so stance legs never stretch beyond this

// Where a leg's foot rests at time t: under its attach joint, turned with it.
Foothold Synthesizer::neutral_foot(size_t leg_index, double t) const {
  const LegRig& leg = rig_.legs[leg_index];
  const double x = std::clamp(t * fps_ + pad_, 0.0, static_cast<double>(total_ - 1));
  const int f0 = static_cast<int>(std::floor(x));
  const int f1 = std::min(f0 + 1, total_ - 1);
  const double w = x - f0;
  const Vec3 position = (1.0 - w) * position_[at(f0, leg.attach)] + w * position_[at(f1, leg.attach)];
  const double yaw0 = attach_yaw(f0, leg.attach);
  double yaw1 = attach_yaw(f1, leg.attach);
  yaw1 = yaw0 + std::remainder(yaw1 - yaw0, 2.0 * kPi);
  const double yaw = (1.0 - w) * yaw0 + w * yaw1;
  Foothold hold;
  hold.position = flat(position) + yaw_rotation(yaw) * leg.neutral_from_attach;
  hold.position.y() = 0.0;
  hold.yaw = yaw;
  return hold;
}

// Swing intervals of one leg for the whole extended timeline.
std::vector<Swing> Synthesizer::leg_swings(size_t leg_index) const {
  std::vector<Swing> swings;
  const LegRig& leg = rig_.legs[leg_index];
  const double t_first = time(0);
  const double t_last = time(total_ - 1);
  const double T = spec_.seconds;
  const double k = std::min(1.0, T / 3.0);
  const Action action = spec_.action;
  if (is_gait(action) && frequency_ > 0.0 && leg_index < gait_.phases.size()) {
    const double phase = gait_.phases[leg_index];
    const double beta = gait_.duty_factor;
    const long first = static_cast<long>(std::floor(frequency_ * t_first)) - 2;
    const long last = static_cast<long>(std::ceil(frequency_ * t_last)) + 2;
    for (long n = first; n <= last; ++n) {
      const double begin = (n + beta - phase) / frequency_;
      const double end = (n + 1 - phase) / frequency_;
      if (begin < move_begin_ || begin >= move_end_) continue;
      swings.push_back({begin, end, SwingStyle::Step});
    }
    return swings;
  }
  switch (action) {
    case Action::Jump: {
      // Feet leave the ground in order from front to back within a few frames; land together.
      const double lift_off = event_b_ + 0.15 * k + 0.01 * leg.pair;
      swings.push_back({lift_off, event_c_, SwingStyle::Tuck});
      break;
    }
    case Action::TakeOff:
      swings.push_back({event_b_ + 0.01 * leg.pair, kInfinity, SwingStyle::Tuck});
      break;
    case Action::Fly:
    case Action::Glide:
      swings.push_back({-kInfinity, kInfinity, SwingStyle::Tuck});
      break;
    case Action::Attack:
      if ((creature_.plan == BodyPlan::Spider || creature_.plan == BodyPlan::Hexapod) && leg.pair == 0) {
        swings.push_back({event_a_ + 0.05, event_d_, SwingStyle::Strike});
      }
      break;
    case Action::Kick:
      if (leg.side == spec_.side && leg.pair == 0) swings.push_back({event_a_, event_d_, SwingStyle::Kick});
      break;
    case Action::JumpingJacks:
      for (int hop = 0; hop < 2 * jack_count(); ++hop) {
        const double begin = event_a_ + hop * 0.5 * kJackSeconds;
        swings.push_back({begin, begin + kJackAirSeconds, SwingStyle::Step});
      }
      break;
    case Action::Dance:
      // Step-touch: each foot lifts and sets down on every other beat, where the swaying hips put it.
      for (int beat = leg.side == Side::Left ? 0 : 1; event_a_ + (beat + 1) / kDanceBeat <= event_d_; beat += 2) {
        const double begin = event_a_ + beat / kDanceBeat;
        swings.push_back({begin, begin + 0.5 / kDanceBeat, SwingStyle::Step});
      }
      break;
    default:
      break;
  }
  return swings;
}

Vec3 Synthesizer::swing_position(size_t leg_index, const Swing& swing, const Vec3& from, const Vec3& to, double t,
                                 int f) const {
  const LegRig& leg = rig_.legs[leg_index];
  const double yaw = attach_yaw(f, leg.attach);
  const Quat heading = yaw_rotation(yaw);
  const Vec3 hip = position_[at(f, leg.joints[0])];
  const double r = leg.reach;
  const bool open_ended = !std::isfinite(swing.end) || !std::isfinite(swing.begin);
  const double u = open_ended ? 0.5 : std::clamp((t - swing.begin) / (swing.end - swing.begin), 0.0, 1.0);
  switch (swing.style) {
    case SwingStyle::Step: {
      const double height = std::min(tuning_.step_height * r * step_scale_, 0.45 * r);
      const double travel = (to - from).norm();
      const double lift = std::min(height, std::max(0.35 * height, 0.6 * travel));
      Vec3 p = from + (to - from) * smoothstep(u);
      p.y() = from.y() + (to.y() - from.y()) * u + lift * std::sin(kPi * u);
      return p;
    }
    case SwingStyle::Tuck: {
      // Folded under the body, trailing a little.
      const Vec3 tucked =
          hip + heading * Vec3(0.5 * leg.end_from_hip.x(), -0.55 * r, 0.5 * leg.end_from_hip.z() - 0.2 * r);
      double w;
      if (!std::isfinite(swing.begin)) {
        w = 1.0;
      } else if (!std::isfinite(swing.end)) {
        w = smoothstep((t - swing.begin) / 0.3);
      } else {
        w = smoothstep(u / 0.3) * smoothstep((1.0 - u) / 0.3);
      }
      const Vec3 line = std::isfinite(swing.end) && std::isfinite(swing.begin) ? Vec3(from + (to - from) * smoothstep(u)) : from;
      return (1.0 - w) * line + w * tucked;
    }
    case SwingStyle::Kick: {
      // Knee up (the foot under it, forward), the leg snaps out to hip height, back to the knee-up pose, down.
      const double x = 0.8 * leg.end_from_hip.x();
      const Vec3 chambered = hip + heading * Vec3(x, -0.6 * r, 0.35 * r);
      const Vec3 extended = hip + heading * Vec3(x, -0.15 * r, 0.9 * r);
      const double span = swing.end - swing.begin;
      const double snap = std::clamp((event_b_ - swing.begin) / span, 0.2, 0.6);
      const double back = std::clamp((event_c_ - swing.begin) / span, snap + 0.05, 0.85);
      if (u < snap) return from + (chambered - from) * smoothstep(u / snap);
      if (u < back) {
        const double w = (u - snap) / (back - snap);
        return chambered + (extended - chambered) * std::sin(kPi * w);  // out and back within [snap, back)
      }
      return chambered + (to - chambered) * smoothstep((u - back) / (1.0 - back));
    }
    case SwingStyle::Strike: {
      const Vec3 raised = hip + heading * Vec3(0.6 * leg.end_from_hip.x(), 0.3 * r, 0.45 * r + std::max(0.0, leg.end_from_hip.z()));
      const Vec3 ground_ahead = from + heading * Vec3(0.0, 0.0, 0.35 * r);
      // Timeline within the swing: rise, hold, strike down, return.
      const double strike_at = std::clamp((event_b_ - swing.begin) / (swing.end - swing.begin), 0.3, 0.7);
      if (u < strike_at - 0.08) {
        const double w = smoothstep(u / (strike_at - 0.08));
        Vec3 p = from + (raised - from) * w;
        p.y() += 0.1 * r * std::sin(kPi * w);
        return p;
      }
      if (u < strike_at + 0.05) {
        const double w = smoothstep((u - (strike_at - 0.08)) / 0.13);
        return raised + (ground_ahead - raised) * w;
      }
      const double w = smoothstep((u - (strike_at + 0.05)) / (1.0 - strike_at - 0.05));
      Vec3 p = ground_ahead + (to - ground_ahead) * w;
      p.y() += 0.12 * r * std::sin(kPi * w);
      return p;
    }
  }
  return from;
}

void Synthesizer::plan_legs() {
  const size_t legs = rig_.legs.size();
  swings_.assign(legs, {});
  targets_.assign(legs, std::vector<Vec3>(total_, Vec3::Zero()));
  foot_yaw_.assign(legs, std::vector<double>(total_, 0.0));
  stance_.assign(legs, std::vector<uint8_t>(total_, 1));
  const double t_first = time(0);
  const double t_last = time(total_ - 1);
  const double T = spec_.seconds;
  for (size_t i = 0; i < legs; ++i) {
    if (!rig_.legs[i].usable) continue;
    swings_[i] = leg_swings(i);
    const std::vector<Swing>& swings = swings_[i];
    // Stance footholds: the neutral point at mid-stance; open-ended stances use
    // the clip's first or last pose.
    std::vector<Foothold> holds(swings.size() + 1);
    for (size_t s = 0; s <= swings.size(); ++s) {
      const double begin = s == 0 ? -kInfinity : swings[s - 1].end;
      const double end = s == swings.size() ? kInfinity : swings[s].begin;
      double when;
      if (!std::isfinite(begin) && !std::isfinite(end)) {
        when = 0.0;
      } else if (!std::isfinite(begin)) {
        when = std::min(end, 0.0);
      } else if (!std::isfinite(end)) {
        when = std::max(begin, T);
      } else {
        when = 0.5 * (begin + end);
      }
      holds[s] = neutral_foot(i, std::clamp(when, t_first, t_last));
      if (spec_.action == Action::JumpingJacks && s % 2 == 1) {  // after a hop out: the feet apart
        const LegRig& leg = rig_.legs[i];
        holds[s].position += yaw_rotation(holds[s].yaw) * Vec3(side_sign(leg.side) * 0.3 * leg.reach, 0.0, 0.0);
      }
    }
    size_t next = 0;  // first swing that has not ended
    for (int f = 0; f < total_; ++f) {
      const double t = time(f);
      while (next < swings.size() && swings[next].end <= t) ++next;
      if (next < swings.size() && swings[next].begin < t) {
        const Swing& swing = swings[next];
        stance_[i][f] = 0;
        targets_[i][f] = swing_position(i, swing, holds[next].position, holds[next + 1].position, t, f);
        // The foot turns while it is in the air: towards its next foothold, or with the body.
        const double body_yaw = attach_yaw(f, rig_.legs[i].attach);
        const double from = holds[next].yaw;
        if (std::isfinite(swing.begin) && std::isfinite(swing.end)) {
          const double u = smoothstep((t - swing.begin) / (swing.end - swing.begin));
          foot_yaw_[i][f] = from + std::remainder(holds[next + 1].yaw - from, 2.0 * kPi) * u;
        } else if (std::isfinite(swing.begin)) {
          foot_yaw_[i][f] = from + std::remainder(body_yaw - from, 2.0 * kPi) * smoothstep((t - swing.begin) / 0.3);
        } else {
          foot_yaw_[i][f] = body_yaw;
        }
      } else {
        stance_[i][f] = 1;
        targets_[i][f] = holds[next].position;
        foot_yaw_[i][f] = holds[next].yaw;
      }
    }
  }
}

// Raises the body in flight phases of fast gaits, lowers it wherever a
// stance foot would be out of reach and raises it where a leg would have to
// fold more than it can.
void Synthesizer::adjust_height() {
  std::vector<double> shift(total_, 0.0);
  if ((spec_.action == Action::Run || spec_.action == Action::Gallop) && !rig_.legs.empty()) {
    std::vector<double> flight(total_, 0.0);
    for (int f = 0; f < total_; ++f) {
      bool any = false;
      for (size_t i = 0; i < rig_.legs.size(); ++i) any = any || (rig_.legs[i].usable && stance_[i][f]);
      flight[f] = any ? 0.0 : 1.0;
    }
    const int half = std::max(1, static_cast<int>(std::lround(0.05 * fps_)));
    for (int f = 0; f < total_; ++f) {
      double sum = 0.0, weight = 0.0;
      for (int g = std::max(0, f - half); g <= std::min(total_ - 1, f + half); ++g) {
        const double w = 1.0 + half - std::abs(g - f);
        sum += w * flight[g];
        weight += w;
      }
      shift[f] = 0.06 * reach_ * (sum / weight) * gait_share(time(f));
    }
  }
  // Drop needed for reach, lift needed for folding.
  std::vector<double> drop(total_, 0.0), lift(total_, 0.0);
  for (int f = 0; f < total_; ++f) {
    for (size_t i = 0; i < rig_.legs.size(); ++i) {
      const LegRig& leg = rig_.legs[i];
      if (!leg.usable || !stance_[i][f]) continue;
      const Vec3 hip = position_[at(f, leg.joints[0])] + Vec3(0.0, shift[f], 0.0);
      const Vec3 end = targets_[i][f] - yaw_rotation(foot_yaw_[i][f]) * (leg.fixed_foot ? leg.foot_vector : Vec3::Zero());
      const double horizontal = flat(hip - end).norm();
      const double limit = kMaxReach * leg.reach;
      const double vertical = std::sqrt(std::max(0.0, limit * limit - horizontal * horizontal));
      drop[f] = std::max(drop[f], (hip.y() - end.y()) - vertical);
      const double fold = 1.05 * leg.min_reach;
      if (horizontal < fold) lift[f] = std::max(lift[f], std::sqrt(fold * fold - horizontal * horizontal) - (hip.y() - end.y()));
    }
  }
  // Smooth envelopes that never fall below the needed drop and lift.
  const int window = std::max(1, static_cast<int>(std::lround(0.15 * fps_)));
  auto envelope = [&](const std::vector<double>& need, int f) {
    double out = 0.0;
    for (int g = std::max(0, f - window); g <= std::min(total_ - 1, f + window); ++g) {
      if (need[g] <= 0.0) continue;
      const double c = std::cos(0.5 * kPi * std::abs(g - f) / (window + 1));
      out = std::max(out, need[g] * c * c);
    }
    return out;
  };
  for (int f = 0; f < total_; ++f) shift[f] += envelope(lift, f) - envelope(drop, f);
  for (int f = 0; f < total_; ++f) {
    if (shift[f] == 0.0) continue;
    root_[f].y() += shift[f];
    for (int j = 0; j < joint_count_; ++j) position_[at(f, j)].y() += shift[f];
  }
}

void Synthesizer::solve_legs() {
  std::vector<Vec3> points;
  for (size_t i = 0; i < rig_.legs.size(); ++i) {
    const LegRig& leg = rig_.legs[i];
    if (!leg.usable) continue;
    const int n = static_cast<int>(leg.joints.size());
    const int ik_joints = static_cast<int>(leg.shape.size());
    for (int f = 0; f < total_; ++f) {
      const Quat parent_global = global_[at(f, leg.attach)];
      const Quat heading = yaw_rotation(heading_angle(parent_global));  // the knee's frame follows the body
      const Quat foot = yaw_rotation(foot_yaw_[i][f]);                   // the foot's stays planted
      const Vec3 hip = position_[at(f, leg.joints[0])];
      const Vec3 tip = targets_[i][f];
      const Vec3 end = leg.fixed_foot ? Vec3(tip - foot * leg.foot_vector) : tip;
      points.assign(ik_joints, hip);
      for (int k = 1; k < ik_joints; ++k) points[k] = heading * leg.shape[k];
      const Vec3 template_end = points[ik_joints - 1];
      const Vec3 wanted = end - hip;
      const Quat align = template_end.norm() > 1e-12 && wanted.norm() > 1e-12 ? Quat::FromTwoVectors(template_end, wanted)
                                                                              : Quat::Identity();
      // Squash the template along the hip-target axis to the target's distance:
      // the bend keeps its direction and FABRIK starts close to the answer.
      const double ratio = template_end.norm() > 1e-12 ? wanted.norm() / template_end.norm() : 1.0;
      const Vec3 axis = wanted.norm() > 1e-12 ? Vec3(wanted.normalized()) : Vec3(0, -1, 0);
      for (int k = 1; k < ik_joints; ++k) {
        const Vec3 p = align * points[k];
        const double along = p.dot(axis);
        points[k] = hip + axis * (along * ratio) + (p - along * axis);
      }
      if (ik_joints == 2) {
        points[1] = hip + wanted.normalized() * leg.lengths[0];
      } else if (ik_joints == 3) {
        points[1] = two_bone_middle(hip, end, leg.lengths[0], leg.lengths[1], points[1] - hip);
        const Vec3 lower = end - points[1];
        points[2] = points[1] + (lower.norm() > 1e-12 ? Vec3(lower.normalized()) : Vec3(0, -1, 0)) * leg.lengths[1];
      } else {
        fabrik(points, leg.lengths, end);
      }
      if (leg.fixed_foot) points.push_back(points.back() + foot * leg.foot_vector);
      Quat* locals = &local_[at(f, 0)];
      const Quat last = aim_chain(skeleton_, leg.joints, points, parent_global, locals);
      locals[leg.joints[n - 1]] = (last.conjugate() * foot).normalized();
    }
  }
}

}  // namespace nec::zoo::detail
