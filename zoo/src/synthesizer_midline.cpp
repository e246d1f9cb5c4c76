// The midline per frame (Synthesizer::pose_midline): spine, neck, head and
// tail; fish swim with a body wave, snakes and centipedes follow their
// undulating path (path_wave); plan-specific strikes of the front body.
#include "synthesizer.h"

#include <algorithm>
#include <cmath>

namespace nec::zoo::detail {

constexpr double kTailLag = 1.8;  // phase lag of the tail tip's sway behind its base, radians

// Snakes and centipedes follow their own path: a sine of this amplitude and
// wavelength (file units) around the travelled centre line.
PathWave Synthesizer::path_wave() const {
  PathWave wave;
  const double body = rig_.body_length;
  if (motion_plan_ == BodyPlan::Snake) {
    wave.amplitude = (spec_.action == Action::Idle ? 0.05 : 0.07) * body;
    wave.wavelength = 0.45 * body;
  } else if (motion_plan_ == BodyPlan::Centipede) {
    wave.amplitude = (spec_.action == Action::Run ? 0.025 : 0.008) * body;
    wave.wavelength = 0.5 * body;
  }
  return wave;
}

// The midline: global rotations of spine, neck, head and tail joints, stored
// in local_ as GLOBAL targets (assemble_frame converts them to locals).
void Synthesizer::pose_midline(int f, double t) {
  const Midline& m = rig_.midline;
  const double heading = heading_[f];
  const double share = gait_share(t);
  const double clock = gait_clock(t);
  const double span = std::max(m.front - m.back, 1e-9);
  const double body = rig_.body_length;
  const Action action = spec_.action;
  const bool path_follower = motion_plan_ == BodyPlan::Snake || motion_plan_ == BodyPlan::Centipede;
  const bool fish = motion_plan_ == BodyPlan::Fish;

  // Curvature of the travelled path (radians per file unit), for bending the
  // body along it; turning on the spot bends as if walking at 2 leg lengths/s.
  const double curvature = turn_[f] / std::max(speed_[f], 2.0 * reach_);

  // Lateral wave: path followers take it from their path; fish beat their
  // tail with a wave running from head to tail, growing towards the tail.
  const PathWave path = path_wave();
  double amplitude = path.amplitude, wavelength = path.wavelength, wave_phase = 0.0;
  if (fish) {
    amplitude = action == Action::Idle ? 0.025 * body : 0.09 * body;
    if (action == Action::Swim) amplitude *= 0.25 + 0.75 * travel_ramp(spec_, t);  // hovering before a start, after a stop
    if (action == Action::Attack) {
      const double burst = pulse(t, event_b_ - 0.05, event_b_ + 0.05, event_c_, event_c_ + 0.3);
      amplitude = (0.05 + 0.08 * burst) * body;
    }
    wavelength = body;
    const double rate = action == Action::Idle     ? 0.7
                        : action == Action::Attack ? 1.8
                                                   : std::clamp(length_speed() / (0.7 * body), 0.8, 4.0);
    wave_phase = 2.0 * kPi * rate * t;
  }

  auto lateral = [&](double s) {  // fish: displacement at arc s, amplitude growing towards the tail
    const double x = (m.front - s) / span;
    return amplitude * (0.1 + 0.9 * x * x) * std::sin(wave_phase + 2.0 * kPi * s / wavelength);
  };
  auto lateral_slope = [&](double s) {
    const double h = 1e-3 * span;
    return (lateral(s + h) - lateral(s - h)) / (2.0 * h);
  };
  // Path follower: yaw of the undulating path at path length u relative to its centre line.
  const double u_now = travelled_[f];
  auto path_yaw = [&](double s) {
    const double u = u_now + s;
    const double k = 2.0 * kPi / wavelength;
    // Heading of the centre line at path length u: find the frame where it was (or will be) travelled.
    double centre_heading = heading;
    if (speed_[f] > 0.0 || length_speed() > 0.0) {
      const auto it = std::lower_bound(travelled_.begin(), travelled_.end(), u);
      const int g = static_cast<int>(std::clamp<long>(it - travelled_.begin(), 0, total_ - 1));
      centre_heading = heading_[g];
    }
    return centre_heading + std::atan(amplitude * k * std::cos(k * u));
  };

  // Secondary motion drivers.
  const double tail_sway_rate = is_gait(action) && frequency_ > 0.0 ? frequency_ : 0.35;
  const double look = (action == Action::Idle || action == Action::FlapWings || action == Action::Sit ||
                       action == Action::LieDown)
                          ? look_amount_ * std::sin(2.0 * kPi * 0.12 * t + look_phase_) *
                                std::min(1.0, t / 0.8 + 0.2)
                          : 0.0;
  const double breath = std::sin(2.0 * kPi * breath_rate_ * t + breath_phase_);

  for (int j = 0; j < joint_count_; ++j) {
    if (!m.member[j]) continue;
    const LimbKind kind = m.kind[j];
    const bool is_root = j == 0;
    const double s = m.bone_mid[j];
    const int index = m.chain_index[j];
    double yaw = heading;
    double pitch = pitch_[f];
    double roll = kind == LimbKind::Spine ? roll_[f] : 0.0;

    if (path_follower) {
      yaw = path_yaw(s);
    } else {
      yaw += std::clamp(curvature * s, -radians(35.0), radians(35.0));
      if (fish) yaw += std::atan(lateral_slope(s));
    }
    if (is_root) yaw += root_yaw_[f];

    switch (kind) {
      case LimbKind::Spine:
        if (!is_root) {
          const int spine_index = std::max(m.spine_index[j], 0);
          const double up_the_spine = std::min(1.0, spine_index / 3.0);
          // Bipeds: the chest counter-rotates against the pelvis; everyone breathes.
          if (motion_plan_ == BodyPlan::Biped || motion_plan_ == BodyPlan::Bird) {
            yaw -= (root_yaw_[f] * 1.6) * up_the_spine;
          }
          pitch += radians(1.2) * breath * up_the_spine;
          if ((motion_plan_ == BodyPlan::Quadruped || motion_plan_ == BodyPlan::Dragon) && action == Action::Walk) {
            yaw += radians(3.0) * share * std::sin(2.0 * kPi * clock - 2.0 * kPi * s / span);
          }
        }
        break;
      case LimbKind::Neck:
      case LimbKind::Head: {
        // Keep the head steadier than the body; look around when standing; nod with the gait.
        const int neck_count = std::max(rig_.midline.neck_length, 1);
        const double share_of_neck = 1.0 / neck_count;
        pitch = 0.4 * pitch_[f];
        yaw += look * share_of_neck * 1.2 + 0.25 * turn_[f] * share_of_neck;
        if (is_gait(action) && motion_plan_ != BodyPlan::Biped) {
          // Nod twice per stride, each joint a little behind the one below it.
          pitch += radians(3.0) * share * std::sin(4.0 * kPi * clock - 0.3 * index) * share_of_neck * 2.0;
        }
        if (action == Action::Attack) {
          const double windup = pulse(t, event_a_, event_b_ - 0.05, event_b_ - 0.05, event_b_);
          const double strike = pulse(t, event_b_ - 0.05, event_b_ + 0.08, event_c_, event_d_);
          switch (motion_plan_) {
            case BodyPlan::Bird: {
              const double pecks = 0.5 - 0.5 * std::cos(2.0 * kPi * 3.0 * (t - event_a_) / (event_d_ - event_a_));
              const double active = pulse(t, event_a_, event_a_ + 0.05, event_d_ - 0.05, event_d_);
              pitch -= radians(45.0) * pecks * active * share_of_neck * 2.0;
              break;
            }
            case BodyPlan::Snake:
            case BodyPlan::Centipede:
              break;
            default:
              pitch += (radians(25.0) * windup - radians(35.0) * strike) * share_of_neck * 2.0;
              break;
          }
        }
        if (action == Action::Eat) {
          // Down to the ground (plan_feeding), nibbling while there.
          const auto it = std::find(feeding_joints_.begin(), feeding_joints_.end(), j);
          if (it != feeding_joints_.end()) {
            const double down = pulse(t, event_a_, event_b_, event_c_, event_d_);
            const double grazing = pulse(t, event_b_, event_b_ + 0.2, event_c_ - 0.2, event_c_);
            pitch = pitch_[f] + down * feeding_joint_pitch_[static_cast<size_t>(it - feeding_joints_.begin())] +
                    radians(4.0) * grazing * std::sin(2.0 * kPi * 1.3 * t) * share_of_neck;
            yaw = heading + radians(6.0) * grazing * std::sin(2.0 * kPi * 0.3 * t + look_phase_) * share_of_neck;
          }
        }
        if (action == Action::Shake) {  // the head whips round a little behind the body
          const double shaking = pulse(t, event_a_, event_b_, event_c_, event_d_);
          yaw += radians(18.0) * shaking * share_of_neck * std::sin(2.0 * kPi * kShakeRate * (t - event_a_) - 0.6 - 0.3 * index);
        }
        if (action == Action::Fly || action == Action::Glide) pitch = -0.3 * pitch_[f];
        if (action == Action::Sit && motion_plan_ != BodyPlan::Biped) pitch = 0.2 * pitch_[f];
        if (action == Action::Bow) pitch = 1.2 * pitch_[f];  // the head goes down with the bow
        // Targets are global: the manner's head carriage grows along the neck to its full value at the head.
        pitch += manner_.head_pitch * (kind == LimbKind::Head ? 1.0 : std::min(1.0, (index + 1.0) / neck_count));
        break;
      }
      case LimbKind::Tail: {
        const int tail_count = std::max(rig_.midline.tail_length, 1);
        const double along = static_cast<double>(index + 1) / tail_count;
        const double lag = kTailLag * along;  // the tip trails the base by kTailLag radians
        double sway_amount = radians(4.0) * tail_scale_;
        if (is_gait(action)) sway_amount = radians(action == Action::Walk ? 6.0 : 4.0) * tail_scale_;
        if (action == Action::Fly || action == Action::Glide) sway_amount = radians(2.0);
        const bool abdomen = motion_plan_ == BodyPlan::Hexapod || motion_plan_ == BodyPlan::Spider;
        if (abdomen) sway_amount = radians(1.5);  // an arthropod's abdomen barely sways
        if (!fish && !path_follower) {
          yaw += sway_amount * along * std::sin(2.0 * kPi * tail_sway_rate * t - lag + sway_phase_);
        }
        if (action == Action::Shake) {  // the tail whips with the shake, lagging towards its tip
          const double shaking = pulse(t, event_a_, event_b_, event_c_, event_d_);
          yaw += radians(25.0) * shaking * along * std::sin(2.0 * kPi * kShakeRate * (t - event_a_) - lag);
        }
        // Tail carriage: follows the body pitch, raised when running, lowered when resting.
        double carriage = 0.0;
        if (action == Action::Run || action == Action::Gallop || action == Action::Trot) carriage = radians(8.0) * share;
        if (action == Action::Sit || action == Action::LieDown) {
          carriage = -radians(10.0) * ramp_between(t, event_a_, event_b_);
        }
        // Lagged response to the body's vertical motion: the tail droops when the body rises.
        const int delayed = std::clamp(f - static_cast<int>(std::lround(0.06 * (index + 1) * fps_)), 1, total_ - 1);
        const double rise = (root_[delayed].y() - root_[delayed - 1].y()) * fps_;
        const double droop = std::clamp(-0.5 * rise / std::max(reach_, 1e-9), -radians(12.0), radians(12.0)) * along;
        if (!fish && !path_follower) pitch = pitch_[f] - carriage - droop;
        if (path_follower || fish) pitch = 0.0;
        break;
      }
      default:
        break;
    }

    // Plan-specific strikes of the front body.
    if (action == Action::Attack && (motion_plan_ == BodyPlan::Snake || motion_plan_ == BodyPlan::Centipede) &&
        s > 0.0) {
      const double front_share = std::clamp(s / std::max(m.front, 1e-9), 0.0, 1.0);
      const double coil = pulse(t, event_a_, event_b_, event_b_, event_b_ + 0.1);
      const double strike = pulse(t, event_b_, event_b_ + 0.1, event_c_, event_d_);
      if (motion_plan_ == BodyPlan::Snake && front_share > 0.35) {
        const double w = (front_share - 0.35) / 0.65;
        yaw += radians(55.0) * coil * std::sin(2.0 * kPi * w * 1.5) * (1.0 - 0.8 * strike) * (1.0 - w * 0.3);
        pitch = radians(35.0) * (coil + 0.6 * strike) * w * (1.0 - w) * 2.0;
        if (front_share > 0.9) pitch = -radians(15.0) * strike;
      }
      if (motion_plan_ == BodyPlan::Centipede && kind != LimbKind::Spine) {
        pitch = radians(30.0) * coil - radians(25.0) * strike;
        yaw += radians(20.0) * side_sign(spec_.side) * strike;
      }
    }
    if (motion_plan_ == BodyPlan::Snake && kind != LimbKind::Spine && s > 0.6 * m.front &&
        action != Action::Attack) {
      pitch = radians(action == Action::Idle ? 8.0 : 4.0);  // head held a little off the ground
    }

    local_[at(f, j)] = body_rotation(yaw, pitch, roll);
  }
}

}  // namespace nec::zoo::detail
