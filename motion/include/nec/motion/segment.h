// Kinematic segmentation and captioning of long unlabelled takes (the MANN
// dog): cut a take into clips of a few seconds where the activity changes and
// caption every clip from what its root and joints measurably do.
//
//   Clip take = read_bvh("D1_058_KAN01_001.bvh");        // raw file units, +Y up
//   TakeSegmentation cut = segment_take(take);            // 2–6 s clips, "a dog ..."
//   for (const Segment& s : cut.segments)
//     std::cout << s.begin << ".." << s.end << " " << s.captions[0] << "\n";
//   // 0..228 a dog sits / 228..498 a dog stands up and trots, then walks and turns left / ...
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
//
// Cutting: activities shorter than min_phase_seconds are absorbed by their most
// similar neighbour; a change between lying/sitting and being up is moved back
// to where the root starts to move, so the whole transition lands in the later
// clip ("a dog gets up and walks forward", "a dog sits down"); clips shorter
// than min_seconds are merged into a neighbour, clips longer than max_seconds
// split into equal parts. A take shorter than min_seconds gives one clip.
//
// Captions: up to three activities per clip joined by ", then " (activities
// under a seventh of the clip are left out), three deterministic phrasings, the
// canonical one first. Vocabulary: stands (still / in place), turns left/right
// in place, walks / trots / runs (forward, backward, sideways, around; and
// turns left/right, in a circle, left and right), sits (down), lies down, gets
// up / stands up, stops, jumps (up, down).
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

struct SegmentOptions {
  double min_seconds = 2.0;            // shortest clip, e.g. 2 s
  double max_seconds = 6.0;            // longest clip, at least 2 × min_seconds, e.g. 6 s
  std::string creature = "dog";        // noun of the captions: "a dog trots forward"
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
  double min_phase_seconds = 0.5;      // shorter activities are absorbed by their neighbours
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
KinematicSignals measure_kinematics(const Clip& take, const SegmentOptions& options = {});
// measure_kinematics(take).heading alone (forward kinematics and the facing estimate, nothing else).
std::vector<double> measure_heading(const Clip& take);

// Frames [begin, end) of one activity.
struct Phase {
  int begin = 0;
  int end = 0;
  Activity activity = Activity::Stand;
  Turn turn = Turn::None;
};

// Averages over a clip, in the units of KinematicSignals.
struct SegmentMeasurements {
  double seconds = 0.0;
  double mean_speed = 0.0;      // body sizes/s
  double max_speed = 0.0;       // body sizes/s
  double forward_speed = 0.0;   // mean, body sizes/s
  double lateral_speed = 0.0;   // mean, body sizes/s, + = left
  double turn_rate = 0.0;       // net heading change / duration, degrees/s, + = left
  double heading_change = 0.0;  // degrees, + = left
  double height_ratio = 0.0;    // median
  double min_height_ratio = 0.0;
  double trunk_pitch = 0.0;         // median, degrees
  double max_rise = 0.0;            // highest root rise above the standing level, × standing height
  double max_vertical_speed = 0.0;  // fastest upward root speed, body sizes/s
  double joint_speed = 0.0;         // mean, body sizes/s
};

struct Segment {
  int begin = 0;                        // first frame
  int end = 0;                          // one past the last frame
  Activity activity = Activity::Stand;  // of the longest phase
  Turn turn = Turn::None;               // from the net turning rate of the whole clip
  bool jumps = false;                   // a jump phase lies inside
  std::vector<Phase> phases;            // activities inside, in time order, clipped to the segment
  std::vector<std::string> labels;      // e.g. {"walks", "turns left"}; from: stands, stands still,
                                        // sits, lies down, walks, trots, runs, turns left, turns right, jumps
  std::vector<std::string> captions;    // canonical first, then paraphrases
  SegmentMeasurements measurements;
};

struct TakeSegmentation {
  KinematicSignals signals;
  std::vector<Phase> phases;      // smoothed activities of the whole take
  std::vector<Segment> segments;  // cover every frame, in order, without overlap
};

// Throws std::invalid_argument for invalid options or a take whose fps is not positive.
TakeSegmentation segment_take(const Clip& take, const SegmentOptions& options = {});

// Measurements of frames [begin, end) of a take.
SegmentMeasurements measure_segment(const KinematicSignals& signals, int begin, int end);

}  // namespace nec
