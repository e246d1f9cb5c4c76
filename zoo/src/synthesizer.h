// Internal to motion synthesis: the Synthesizer, which makes one clip from a
// creature's rig and an effective spec, and the swing and foothold types of
// its legs. Its steps live in synthesizer_*.cpp and motion_synthesis.cpp.
#pragma once

#include "motion_limits.h"

#include <cstdint>
#include <vector>

namespace nec::zoo::detail {

struct PathWave {
  double amplitude = 0.0;   // file units, 0 for bodies that do not follow a path
  double wavelength = 1.0;  // file units
};

enum class SwingStyle {
  Step,    // arc from one foothold to the next
  Tuck,    // follows the body, folded under it (jumps, flight)
  Strike,  // rises in front of the body and strikes the ground ahead (attacks)
  Kick,    // knee up, the leg snaps out forward at hip height and back, then down where it stood
};

// Where a foot stands: the tip on the ground and the foot's heading.
struct Foothold {
  Vec3 position = Vec3::Zero();
  double yaw = 0.0;  // radians about +Y
};

struct Swing {
  double begin = 0.0;
  double end = 0.0;  // kInfinity: the foot never lands again
  SwingStyle style = SwingStyle::Step;
};

// Makes one clip: the root trajectory and body per frame (plan_body), then the
// legs (plan_legs, adjust_height, solve_legs); run() does it all, once.
class Synthesizer {
 public:
  Synthesizer(const Creature& creature, const Rig& rig, const MotionSpec& spec);
  SynthesizedMotion run();

 private:
  double time(int f) const { return (f - pad_) / fps_; }
  size_t at(int f, int j) const { return static_cast<size_t>(f) * joint_count_ + j; }
  double length_speed() const { return spec_.speed * rig_.body_length; }  // file units per second

  PathWave path_wave() const;
  void plan_travel();
  void plan_body();
  void pose_midline(int f, double t);
  void pose_appendages(int f, double t);
  void assemble_frame(int f);
  void pose_wing(const Appendage& wing, int f, double t);
  void plan_feeding();
  // Jumping jacks: where the clip is in the current jack.
  struct JackPhase {
    double air = 0.0;      // 0..1 through a hop while the feet are off the ground, 0 on it
    double landing = 0.0;  // 0..1..0 over the stance after a hop (knees giving)
    double spread = 0.0;   // 0 feet together and arms down, 1 feet apart and arms overhead
  };
  static constexpr double kJackSeconds = 1.0;     // one jack: a hop out and a hop in
  static constexpr double kJackAirSeconds = 0.2;  // each hop's time in the air
  static constexpr double kShakeRate = 4.5;       // shakes per second
  static constexpr double kDanceBeat = 2.0;       // dance steps per second
  int jack_count() const;
  JackPhase jack_phase(double t) const;
  struct ArmGesture {
    double weight = 0.0;           // 0: the ordinary arm pose, 1: fully in the gesture
    Vec3 upper = -Vec3::UnitY();   // upper arm direction in the chest's heading frame
    Vec3 lower = -Vec3::UnitY();   // forearm direction, same frame
  };
  ArmGesture arm_gesture(const Appendage& arm, int f, double t) const;
  void plan_legs();
  std::vector<Swing> leg_swings(size_t leg) const;
  void adjust_height();
  void solve_legs();

  // Helpers.
  double gait_clock(double t) const { return frequency_ * t; }
  double gait_share(double t) const;  // 0 when standing still, 1 at full gait
  Foothold neutral_foot(size_t leg, double t) const;
  double attach_yaw(int f, int attach) const { return heading_angle(global_[at(f, attach)]); }
  Vec3 swing_position(size_t leg, const Swing& swing, const Vec3& from, const Vec3& to, double t, int f) const;

  const Creature& creature_;
  const BodyPlan motion_plan_;  // moves_like(creature_.plan): whose motion rules apply
  const Skeleton& skeleton_;
  const Rig& rig_;
  MotionSpec spec_;
  SplitMix64 style_;
  int joint_count_ = 0;
  int frames_ = 0;
  int pad_ = 0;
  int total_ = 0;
  double fps_ = 30.0;
  double reach_ = 1.0;  // leg reach or a body-size stand-in, file units

  GaitPattern gait_;
  double frequency_ = 0.0;
  GaitTuning tuning_;
  double move_begin_ = -kInfinity;  // gait swings may start in [move_begin_, move_end_)
  double move_end_ = kInfinity;

  // What the spec's manner does to the body (MotionSpec::manner), set once from it.
  struct MannerShape {
    double trunk_pitch = 0.0;  // radians added to the body's pitch, + = nose up
    double head_pitch = 0.0;   // radians added to the neck and head, + = up
    double arm_swing = 1.0;    // scale of the arms' swing in a gait
    double step = 1.0;         // scale of the step height
    double lower = 0.0;        // body lowered by this share of the leg reach (negative: raised)
    double bounce = 0.0;       // vertical bob in a gait, share of the leg reach
  };
  MannerShape manner_;

  // Style drawn from the seed.
  double breath_rate_ = 0.3, breath_phase_ = 0.0, look_phase_ = 0.0, look_amount_ = 0.3, sway_phase_ = 0.0;
  double step_scale_ = 1.0, tail_scale_ = 1.0;

  // Per extended frame (total_).
  std::vector<double> heading_;   // radians about +Y, + = left
  std::vector<double> speed_;     // file units per second along the heading
  std::vector<double> turn_;      // radians per second
  std::vector<double> travelled_; // path length so far (0 at t = 0)
  std::vector<Vec3> root_;        // root position
  std::vector<double> pitch_, roll_;
  std::vector<double> root_yaw_;  // root yaw relative to the heading
  // Action timeline (seconds), set by plan_body for the actions that use them.
  double event_a_ = 0.0, event_b_ = 0.0, event_c_ = 0.0, event_d_ = 0.0;
  double altitude_ = 0.0;
  // Eat: how far the body tips forward (radians, negative: nose down) and the global pitch each neck joint
  // and the head add at the lowest pose (plan_feeding).
  double feeding_pitch_ = 0.0;
  std::vector<int> feeding_joints_;
  std::vector<double> feeding_joint_pitch_;

  std::vector<Quat> local_;       // (total_, J)
  std::vector<Quat> global_;      // (total_, J) body FK (legs at rest)
  std::vector<Vec3> position_;    // (total_, J)

  // Legs.
  std::vector<std::vector<Swing>> swings_;   // per leg
  std::vector<std::vector<Vec3>> targets_;   // per leg, (total_) tip target
  std::vector<std::vector<double>> foot_yaw_; // per leg, (total_) heading of the foot: fixed while planted
  std::vector<std::vector<uint8_t>> stance_; // per leg, (total_)
};

}  // namespace nec::zoo::detail
