// The body per frame (Synthesizer::plan_body): the timelines of jump,
// take-off, sit, lie down and attack, the root's height, pitch, roll and sway
// for every action, then the limbs and midline posed frame by frame.
#include "synthesizer.h"

#include <optional>

#include <algorithm>
#include <cmath>

namespace nec::zoo::detail {

void Synthesizer::plan_body() {
  const double T = spec_.seconds;
  const double k = std::min(1.0, T / 3.0);  // short clips compress the action timelines
  switch (spec_.action) {
    case Action::Jump:
      event_a_ = std::max(0.2 * T, 0.3);        // crouch starts
      event_b_ = event_a_ + 0.35 * k;           // push-off starts
      event_c_ = event_b_ + 0.15 * k + 0.5 * k; // landing (lift-off at b + 0.15k, 0.5k flight)
      event_d_ = event_c_ + 0.7 * k;            // standing again
      break;
    case Action::TakeOff:
      event_a_ = std::max(0.15 * T, 0.25);      // crouch starts
      event_b_ = event_a_ + 0.35 * k;           // lift-off
      break;
    case Action::Sit:
    case Action::LieDown:
      event_a_ = 0.15 * T;
      event_b_ = event_a_ + std::min(1.4, 0.4 * T);
      break;
    case Action::Attack:
      event_a_ = 0.2 * T;                       // wind-up
      event_b_ = event_a_ + 0.45 * k;           // strike
      event_c_ = event_b_ + 0.4 * k;            // strike held, recovery starts
      event_d_ = event_c_ + 0.7 * k;            // recovered
      break;
    case Action::Wave:
    case Action::RaiseHands:
    case Action::Point:
    case Action::Clap:
      event_a_ = 0.12 * T;                      // the arms start to rise
      event_b_ = event_a_ + 0.5 * k;            // in the gesture
      event_d_ = T - 0.08 * T;                  // down again
      event_c_ = std::max(event_b_, event_d_ - 0.5 * k);  // lowering starts
      break;
    case Action::Bow:
      event_a_ = 0.2 * T;                       // starts to bend
      event_b_ = event_a_ + 0.6 * k;            // bowed
      event_c_ = event_b_ + 0.5 * k;            // straightening starts
      event_d_ = event_c_ + 0.7 * k;            // upright
      break;
    case Action::Crouch:
      event_a_ = 0.15 * T;                      // starts to go down
      event_b_ = event_a_ + std::min(1.0, 0.3 * T);  // low, and stays
      break;
    case Action::Eat:
      event_a_ = 0.12 * T;                      // the head starts down
      event_b_ = event_a_ + std::min(1.2, 0.3 * T);  // at the ground: grazing
      event_c_ = std::max(event_b_, 0.8 * T);   // looks up
      event_d_ = std::max(event_c_, 0.95 * T);  // head up again
      plan_feeding();
      break;
    case Action::Shake:
      event_a_ = 0.25 * T;                      // starts to shake
      event_b_ = event_a_ + 0.2 * k;            // shaking hard
      event_d_ = std::min(0.88 * T, event_b_ + 1.6);  // still again
      event_c_ = std::max(event_b_, event_d_ - 0.25 * k);
      break;
    case Action::JumpingJacks:
    case Action::Dance:
      event_a_ = 0.12 * T;                      // starts
      event_d_ = 0.9 * T;                       // stops (jumping jacks: after the last whole jack)
      break;
    case Action::Stretch:
      event_a_ = 0.12 * T;                      // the arms start up
      event_b_ = event_a_ + 0.6 * k;            // overhead
      event_d_ = 0.92 * T;                      // down again
      event_c_ = std::max(event_b_, event_d_ - 0.6 * k);  // lowering starts
      break;
    case Action::Kick:
      event_a_ = 0.25 * T;                      // the knee comes up
      event_b_ = event_a_ + 0.3 * k;            // the leg snaps out
      event_c_ = event_b_ + 0.25 * k;           // pulled back
      event_d_ = event_c_ + 0.4 * k;            // the foot is down
      break;
    default:
      break;
  }
  plan_travel();

  // Base heights.
  const double stand = rig_.stand_height;
  altitude_ = stand + 1.5 * rig_.body_length;
  root_yaw_.assign(total_, 0.0);
  pitch_.assign(total_, 0.0);
  roll_.assign(total_, 0.0);
  const double r = reach_;
  for (int f = 0; f < total_; ++f) {
    const double t = time(f);
    double y = stand;
    double pitch = 0.0, roll = 0.0, yaw = 0.0;
    Vec3 local_offset = Vec3::Zero();  // body-frame offset (x left, z forward)
    const double breath = std::sin(2.0 * kPi * breath_rate_ * t + breath_phase_);
    const double share = gait_share(t);
    const double clock = gait_clock(t);
    switch (spec_.action) {
      case Action::Idle:
      case Action::FlapWings:
      case Action::Wave:
      case Action::RaiseHands:
      case Action::Point:
      case Action::Clap:
        y += 0.008 * r * breath;
        local_offset.x() = 0.02 * r * std::sin(2.0 * kPi * 0.13 * t + sway_phase_);
        if (spec_.action == Action::FlapWings) {
          const double flap = std::sin(2.0 * kPi * (motion_plan_ == BodyPlan::Dragon ? 1.3 : 2.6) * t);
          y += 0.03 * r * flap * pulse(t, 0.2, 0.5, T - 0.5, T - 0.2);
        }
        break;
      case Action::Walk:
      case Action::Trot:
      case Action::Run:
      case Action::Gallop:
      case Action::Turn: {
        if (creature_.plan == BodyPlan::Hopper) {
          // Both feet push off together: the body flies between hops, nose up at take-off and down to land.
          const double phase = clock - std::floor(clock);
          const double duty = gait_.duty_factor;
          const double u = phase < duty ? 0.0 : (phase - duty) / (1.0 - duty);
          y += (spec_.action == Action::Run ? 0.3 : 0.18) * r * 4.0 * u * (1.0 - u) * share;
          pitch = radians(6.0) * std::sin(2.0 * kPi * phase) * share;
        } else if (motion_plan_ == BodyPlan::Biped || motion_plan_ == BodyPlan::Bird) {
          yaw = radians(spec_.action == Action::Run ? 7.0 : 5.0) * std::sin(2.0 * kPi * clock) * share;
          roll = radians(2.0) * std::sin(2.0 * kPi * clock) * share;
          local_offset.x() = 0.025 * r * std::sin(2.0 * kPi * clock + 0.5 * kPi) * share;
          pitch = -radians(spec_.action == Action::Run ? 8.0 : 2.0) * share;
        } else if (spec_.action == Action::Gallop) {
          pitch = radians(5.0) * std::sin(2.0 * kPi * clock) * share;
        } else if (spec_.action == Action::Trot) {
          roll = radians(1.5) * std::sin(2.0 * kPi * clock) * share;
        }
        break;
      }
      case Action::Jump: {
        const double t_lo = event_b_ + 0.15 * k;
        const double crouch = 0.22 * r;
        const double launch = 0.06 * r;
        const double apex = 0.45 * r;
        if (t < event_b_) {
          y -= crouch * ramp_between(t, event_a_, event_b_);
        } else if (t < t_lo) {
          y += (-crouch) + (crouch + launch) * ramp_between(t, event_b_, t_lo);
        } else if (t < event_c_) {
          const double u = (t - t_lo) / (event_c_ - t_lo);
          y += launch + 4.0 * apex * u * (1.0 - u);
        } else {
          const double absorb = 0.2 * r;
          const double down = ramp_between(t, event_c_, event_c_ + 0.2 * k);
          const double up = ramp_between(t, event_c_ + 0.25 * k, event_d_);
          y += launch * (1.0 - down) - absorb * down * (1.0 - up);
        }
        pitch = -radians(8.0) * pulse(t, event_a_, event_b_, event_b_, t_lo) +
                radians(6.0) * pulse(t, t_lo, t_lo + 0.1, event_c_ - 0.2 * k, event_c_) -
                radians(6.0) * pulse(t, event_c_, event_c_ + 0.1, event_c_ + 0.2, event_d_);
        break;
      }
      case Action::Sit: {
        const double w = ramp_between(t, event_a_, event_b_);
        if (motion_plan_ == BodyPlan::Biped) {
          // Squat down and back onto the ground, leaning forward on the way.
          y = stand + (0.3 * r - stand) * w;
          local_offset.z() = -0.45 * r * w;
          pitch = -radians(25.0) * pulse(t, event_a_, 0.5 * (event_a_ + event_b_), 0.5 * (event_a_ + event_b_), event_b_ + 0.3) -
                  radians(5.0) * w;
        } else if (motion_plan_ == BodyPlan::Bird) {
          y = stand + (0.45 * r - stand) * w;
        } else {
          // Hindquarters down, chest up on straight front legs.
          const double hips = std::min(0.4 * r, 0.7 * stand);  // (a primate's reach is its arm's)
          y = stand + (hips - stand) * w;
          local_offset.z() = -0.1 * r * w;
          double chest_rise = 0.0;
          for (const LegRig& leg : rig_.legs) {
            if (!leg.usable || leg.pair != 0) continue;
            const Vec3 shoulder = leg.hip_rest;
            const double radius = std::hypot(shoulder.y(), shoulder.z());
            const double phi = std::atan2(shoulder.y(), shoulder.z());
            const double wanted = (stand + shoulder.y() - 0.05 * r) - hips;
            if (radius > 1e-9) chest_rise = std::asin(std::clamp(wanted / radius, -0.8, 0.8)) - phi;
            break;
          }
          pitch = std::clamp(chest_rise, 0.0, radians(40.0)) * w;
        }
        y += 0.006 * r * breath * w;
        break;
      }
      case Action::Bow: {
        // Bends at the hips: the pelvis tips forward and slides back a little over planted feet.
        const double bow = pulse(t, event_a_, event_b_, event_c_, event_d_);
        pitch = -radians(50.0) * bow;
        local_offset.z() = -0.12 * r * bow;
        y -= 0.04 * r * bow;
        break;
      }
      case Action::Crouch: {
        const double w = ramp_between(t, event_a_, event_b_);
        y -= 0.4 * r * w;
        local_offset.z() = -0.1 * r * w;
        pitch = -radians(20.0) * w;
        y += 0.006 * r * breath * w;
        break;
      }
      case Action::Kick: {
        // Leans back as the leg goes out.
        const double kick = pulse(t, event_a_, event_b_, event_c_, event_d_);
        pitch = radians(10.0) * kick;
        y += 0.008 * r * breath;
        break;
      }
      case Action::LieDown: {
        const double w = ramp_between(t, event_a_, event_b_);
        const bool sprawler = motion_plan_ == BodyPlan::Hexapod || motion_plan_ == BodyPlan::Spider ||
                              motion_plan_ == BodyPlan::Centipede;
        const double low = sprawler ? 0.12 * r : 0.32 * r;
        y = stand + (std::min(low, stand) - stand) * w;
        y += 0.006 * r * breath;
        break;
      }
      case Action::Attack: {
        const double windup = pulse(t, event_a_, event_b_ - 0.05, event_b_ - 0.05, event_b_);
        const double strike = pulse(t, event_b_ - 0.05, event_b_ + 0.08, event_c_, event_d_);
        switch (motion_plan_) {
          case BodyPlan::Biped:
            yaw = radians(25.0) * side_sign(spec_.side) * (windup - 1.4 * strike);
            local_offset.z() = 0.08 * r * strike;
            break;
          case BodyPlan::Hexapod:
          case BodyPlan::Spider:
            pitch = radians(18.0) * pulse(t, event_a_, event_b_, event_b_ + 0.05, event_c_) - radians(6.0) * strike;
            local_offset.z() = -0.1 * r * windup + 0.15 * r * strike;
            y -= 0.05 * r * windup;
            break;
          case BodyPlan::Bird: {
            // Three quick pecks.
            const double peck = pulse(t, event_a_, event_b_, event_d_ - 0.2, event_d_);
            pitch = -radians(20.0) * peck;
            break;
          }
          case BodyPlan::Fish:
          case BodyPlan::Snake:
          case BodyPlan::Centipede:
            break;
          default:
            local_offset.z() = -0.12 * r * windup + 0.3 * r * strike;
            y -= 0.08 * r * windup + 0.04 * r * strike;
            pitch = radians(6.0) * windup - radians(8.0) * strike;
            yaw = radians(12.0) * side_sign(spec_.side) * strike;
            break;
        }
        y += 0.008 * r * breath;
        break;
      }
      case Action::Shake: {
        // The body rolls fast from side to side, braced on its legs.
        const double shaking = pulse(t, event_a_, event_b_, event_c_, event_d_);
        roll = radians(14.0) * shaking * std::sin(2.0 * kPi * kShakeRate * (t - event_a_));
        y -= 0.04 * r * shaking;
        break;
      }
      case Action::JumpingJacks: {
        const JackPhase jack = jack_phase(t);
        y += 0.07 * r * std::sin(kPi * jack.air) - 0.03 * r * jack.landing;
        break;
      }
      case Action::Stretch: {
        // Arches back with the arms up, then bends to one side and the other.
        const double up = pulse(t, event_a_, event_b_, event_c_, event_d_);
        const double lean = pulse(t, event_b_, event_b_ + 0.2, event_c_ - 0.2, event_c_);
        pitch = radians(8.0) * up;
        roll = radians(12.0) * lean * std::sin(2.0 * kPi * (t - event_b_) / std::max(event_c_ - event_b_, 1e-3));
        y += 0.006 * r * breath;
        break;
      }
      case Action::Dance: {
        // Sways side to side over two beats, bounces on each, the hips turning with the sway.
        const double dancing = pulse(t, event_a_, event_a_ + 0.3, event_d_ - 0.3, event_d_);
        const double sway = std::sin(kPi * kDanceBeat * (t - event_a_));
        local_offset.x() = 0.07 * r * sway * dancing;
        yaw = radians(12.0) * sway * dancing;
        y -= 0.04 * r * dancing * (0.5 + 0.5 * std::cos(2.0 * kPi * kDanceBeat * (t - event_a_)));
        break;
      }
      case Action::Eat: {
        const double down = pulse(t, event_a_, event_b_, event_c_, event_d_);
        y += 0.006 * r * breath - 0.05 * r * down;
        pitch = feeding_pitch_ * down;
        break;
      }
      case Action::TakeOff: {
        const double crouch = 0.18 * r * pulse(t, event_a_, event_b_ - 0.12 * k, event_b_ - 0.12 * k, event_b_);
        const double climb = t > event_b_ ? (t - event_b_) : 0.0;
        const double rise = (0.5 * r) * ramp_between(t, event_b_ - 0.12 * k, event_b_ + 0.3 * k) +
                            0.35 * rig_.body_length * climb * climb / std::max(T - event_b_, 0.5);
        y = stand - crouch + rise;
        pitch = radians(14.0) * pulse(t, event_b_ - 0.1, event_b_ + 0.3, T - 0.6, T + 1.0) - radians(10.0) * crouch / r;
        break;
      }
      case Action::Fly: {
        const double flap_rate = motion_plan_ == BodyPlan::Dragon ? 1.4 : 3.0;
        y = altitude_ + 0.03 * rig_.body_length * std::sin(2.0 * kPi * flap_rate * t + 0.5 * kPi);
        roll = -std::clamp(0.6 * turn_[f], -radians(35.0), radians(35.0));
        pitch = radians(3.0);
        break;
      }
      case Action::Glide:
        y = altitude_ + 0.1 * length_speed() * (0.5 * T - t);
        roll = -std::clamp(0.7 * turn_[f], -radians(40.0), radians(40.0));
        pitch = -radians(3.0) + radians(1.5) * std::sin(2.0 * kPi * 0.4 * t + sway_phase_);
        break;
      case Action::Swim:
      case Action::Slither:
        y = rig_.rest_height;
        break;
      default:
        break;
    }
    if (takes_manner(spec_.action)) {
      pitch += manner_.trunk_pitch;
      y -= manner_.lower * r;
      y += manner_.bounce * r * std::abs(std::sin(2.0 * kPi * clock)) * share;
    }
    if (motion_plan_ == BodyPlan::Fish) {
      y = std::max(rig_.rest_height, 0.4 * rig_.body_length);
      if (spec_.action == Action::Idle) y += 0.01 * rig_.body_length * breath;
    }
    if (motion_plan_ == BodyPlan::Snake) y = rig_.rest_height;
    // Path followers sit on their undulating path, off the centre line.
    const PathWave wave = path_wave();
    if (wave.amplitude > 0.0) {
      local_offset.x() += wave.amplitude * std::sin(2.0 * kPi * travelled_[f] / wave.wavelength);
    }
    const Vec3 offset = yaw_rotation(heading_[f]) * local_offset;
    root_[f] = Vec3(root_[f].x() + offset.x(), y, root_[f].z() + offset.z());
    root_yaw_[f] = yaw;
    pitch_[f] = pitch;
    roll_[f] = roll;
  }

  local_.assign(static_cast<size_t>(total_) * joint_count_, Quat::Identity());
  global_.assign(local_.size(), Quat::Identity());
  position_.assign(local_.size(), Vec3::Zero());
  for (int f = 0; f < total_; ++f) {
    const double t = time(f);
    pose_appendages(f, t);
    pose_midline(f, t);
    assemble_frame(f);
  }
}

// Where a grazing head goes: the body tips forward (the front legs bending under it) by as little as lets
// the neck and head reach the ground ahead of the forefeet; the chain from the first neck joint to the tip of
// the head is then solved in the body's sagittal plane (FABRIK, from its rest shape), and each bone's change
// of elevation becomes its joint's global pitch. A neck too short even then stretches towards the ground.
void Synthesizer::plan_feeding() {
  feeding_joints_.clear();
  feeding_joint_pitch_.clear();
  const std::vector<const Limb*> heads = creature_.limbs_of(LimbKind::Head);
  if (heads.empty()) return;
  for (const Limb* neck : creature_.limbs_of(LimbKind::Neck)) feeding_joints_ = neck->joints;
  const int head = heads.front()->joints.back();
  feeding_joints_.push_back(head);
  // The muzzle: the foremost end site of the head or of a joint it carries (a jaw).
  const auto carried_by_head = [&](int j) {
    for (; j >= 0; j = skeleton_.parents[j]) {
      if (j == head) return true;
    }
    return false;
  };
  std::optional<Vec3> muzzle;
  for (const EndSite& site : skeleton_.end_sites) {
    const Vec3 tip = rig_.rest[site.parent] + site.offset;
    if (carried_by_head(site.parent) && (!muzzle || tip.z() > muzzle->z())) muzzle = tip;
  }
  if (!muzzle) {
    feeding_joints_.clear();
    return;
  }
  // Rest points in the sagittal plane (x = 0), relative to the root: the joints, then the muzzle.
  std::vector<Vec3> rest;
  const auto sagittal = [&](const Vec3& p) { return Vec3(0.0, p.y() - rig_.rest[0].y(), p.z() - rig_.rest[0].z()); };
  for (int j : feeding_joints_) rest.push_back(sagittal(rig_.rest[j]));
  rest.push_back(sagittal(*muzzle));
  std::vector<double> lengths;
  double total = 0.0;
  for (size_t i = 0; i + 1 < rest.size(); ++i) {
    lengths.push_back((rest[i + 1] - rest[i]).norm());
    total += lengths.back();
  }
  const double height = rig_.stand_height - 0.05 * reach_;  // the root, lowered a little while feeding
  const auto placed = [&](double pitch) {  // the rest points with the body tipped by `pitch` (+ = nose up)
    std::vector<Vec3> points;
    for (const Vec3& p : rest) {
      points.push_back(Vec3(0.0, height + p.z() * std::sin(pitch) + p.y() * std::cos(pitch),
                            p.z() * std::cos(pitch) - p.y() * std::sin(pitch)));
    }
    return points;
  };
  const double reach = 0.9 * total;
  const double muzzle_height = 0.03 * reach_;
  double pitch = 0.0;
  for (int degrees = 0; degrees <= 25; ++degrees) {
    pitch = -radians(degrees);
    if (placed(pitch).front().y() - muzzle_height <= reach) break;
  }
  const std::vector<Vec3> before = placed(pitch);
  const Vec3& base = before.front();
  const double drop = base.y() - muzzle_height;
  const double ahead = std::sqrt(std::max(reach * reach - drop * drop, std::pow(0.25 * total, 2)));
  std::vector<Vec3> after = before;
  fabrik(after, lengths, Vec3(0.0, muzzle_height, base.z() + std::min(ahead, reach)));
  const auto elevation = [](const Vec3& from, const Vec3& to) { return std::atan2(to.y() - from.y(), to.z() - from.z()); };
  for (size_t i = 0; i + 1 < before.size(); ++i) {
    feeding_joint_pitch_.push_back(elevation(after[i], after[i + 1]) - elevation(before[i], before[i + 1]));
  }
  feeding_pitch_ = pitch;
}

// Jumping jacks: jacks of kJackSeconds from event_a_, each a hop out (the feet apart) and a hop in, whole jacks
// only, done by event_d_.
int Synthesizer::jack_count() const {
  return std::max(1, static_cast<int>(std::floor((event_d_ - event_a_) / kJackSeconds)));
}

Synthesizer::JackPhase Synthesizer::jack_phase(double t) const {
  JackPhase phase;
  const double half = 0.5 * kJackSeconds;
  const double since = t - event_a_;
  if (since < 0.0 || since >= jack_count() * kJackSeconds) return phase;
  const int hop = static_cast<int>(std::floor(since / half));
  const double in_hop = since - hop * half;
  if (in_hop < kJackAirSeconds) {
    phase.air = in_hop / kJackAirSeconds;
  } else {
    phase.landing = std::sin(kPi * (in_hop - kJackAirSeconds) / (half - kJackAirSeconds));
  }
  // The arms go up with the hop out and come down with the hop in.
  const double out = hop % 2 == 0 ? std::min(1.0, in_hop / kJackAirSeconds) : 1.0 - std::min(1.0, in_hop / kJackAirSeconds);
  phase.spread = smoothstep(out);
  return phase;
}

}  // namespace nec::zoo::detail
