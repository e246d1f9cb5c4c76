// Per-frame kinematic measurements of a motion: how fast the root travels,
// which way the body faces and turns, how high it stands, its trunk pitch, and
// an activity per frame (lies, sits, stands, walks, trots, runs, jumps). Kinematic
// segmentation (corpus/segment.h) cuts takes where these change; fitting
// (fitting/) steers and checks a transferred motion by its heading.
//
//   KinematicSignals s = measure_kinematics(clip);     // s.speed[t], s.heading[t], s.activity[t]
//   std::vector<double> h = measure_heading(clip);     // the heading alone, degrees
//
// Conventions. +Y is up (rotate Z-up takes first). Lengths are measured in
// body sizes (Skeleton::diameter()) and rates per second, so thresholds hold
// for any unit and frame rate. Heights are relative to the standing height
// (root above the lowest body point while the creature travels on the ground).
// Headings are angles about +Y; turning left is counter-clockwise seen from
// above (positive), right is negative. The facing direction comes from the
// left/right joint pairs nearest the trunk (left × up), its sign checked
// against the head; without sided joints from the head, else from the root's
// +Z axis.
//
// Per frame: posture from the height ratio and the trunk pitch (low with the
// chest above the root: sits; low otherwise: lies), gait from the horizontal
// speed, turning from the heading rate. A jump is a flight (the lowest body
// point stops resting on a support) during which the body lifts off the floor
// and the root rises above the standing level; the floor of a flight is the
// lower of the supports before and after it, so jumps onto and off a table
// count ("jumps up", "jumps down").
#pragma once

#include "nec/motion/motion.h"

#include <string>
#include <string_view>
#include <vector>

namespace nec {

// Ordered by body height and pace: similarity between activities is their distance.
enum class Activity : unsigned char { Lie, Sit, Stand, Walk, Trot, Run, Jump };
enum class Turn : signed char { Right = -1, None = 0, Left = 1 };

std::string_view activity_name(Activity activity);  // "lie", "sit", "stand", ...
std::string_view turn_name(Turn turn);              // "right", "none", "left"

// Thresholds of the per-frame activities.
struct KinematicOptions {
  double standing_height = 0.0;        // root height above the ground when standing, file units; 0 = estimate
  double standing_height_ratio = 0.5;  // estimate for takes that never move: this × body size (or more)
  double walk_speed = 0.2;             // body sizes/s; slower is standing
  double trot_speed = 1.3;             // body sizes/s; from here on trotting
  double run_speed = 2.8;              // body sizes/s; from here on running (canter, gallop)
  double turn_rate = 25.0;             // degrees/s of heading change that count as turning
  double low_height = 0.65;            // height ratio below which the creature sits or lies
  double sit_pitch = 20.0;             // degrees the chest rises above the root when sitting
  double jump_rise = 0.2;              // root above the standing level, × standing height, for a jump
  double airborne_height = 0.25;       // lowest body point above the floor, × standing height, for a jump
  double contact_speed = 0.3;          // body sizes/s under which the lowest body point rests on a support
  double still_joint_speed = 0.1;      // mean joint speed (body sizes/s) under which standing is "still"
  double velocity_window = 0.5;        // seconds of the centred difference for speeds
  double turn_window = 1.0;            // seconds of the centred difference for the heading rate
  double min_jump_seconds = 0.1;       // shorter flights are not jumps

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

// Per-frame measurements of a take; every vector has T entries.
struct KinematicSignals {
  double fps = 30.0;
  double body_size = 1.0;              // Skeleton::diameter(), file units
  double standing_height = 1.0;        // file units, given or estimated
  std::string standing_height_source;  // "option", "moving frames" or "body size"
  std::string facing_source;           // "left/right joints", "head" or "root +Z axis"
  int chest = -1;                      // joint whose height above the root gives the trunk pitch; -1 none
  std::vector<double> speed;           // horizontal root speed, body sizes/s
  std::vector<double> forward_speed;   // along the facing direction, body sizes/s
  std::vector<double> lateral_speed;   // towards the creature's left, body sizes/s
  std::vector<double> heading;         // unwrapped facing angle about +Y, degrees (+ = left)
  std::vector<double> turn_rate;       // degrees/s, + = left (counter-clockwise from above)
  std::vector<double> height_ratio;    // root above the lowest body point / standing height
  std::vector<double> trunk_pitch;     // degrees, + = chest above the root; 0 without a chest
  std::vector<double> rise;            // root above (floor + standing height) / standing height
  std::vector<double> lift;            // lowest body point above the floor / standing height
  std::vector<double> floor_height;    // height of the support under the body, file units
  std::vector<double> vertical_speed;  // root, body sizes/s, + = up
  std::vector<double> joint_speed;     // mean joint speed, body sizes/s
  std::vector<Activity> activity;      // per-frame classification before smoothing
  std::vector<Turn> turn;

  int frame_count() const { return static_cast<int>(speed.size()); }
};

// Throws std::invalid_argument for invalid options or a take whose fps is not positive.
KinematicSignals measure_kinematics(const Clip& take, const KinematicOptions& options = {});
// measure_kinematics(take).heading alone (forward kinematics and the facing estimate, nothing else).
std::vector<double> measure_heading(const Clip& take);

// Frames of at least one: round(seconds × fps), 1 at the least.
int frames_in(double seconds, double fps);

bool is_upright(Activity activity);  // stands, walks, trots or runs
bool is_moving(Activity activity);   // walks, trots or runs
bool is_low(Activity activity);      // lies or sits

}  // namespace nec
