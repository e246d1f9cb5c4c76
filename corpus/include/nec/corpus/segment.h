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
// Per-frame measurements and activities: motion/kinematic_signals.h.
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

#include "nec/motion/kinematic_signals.h"

#include <string>
#include <string_view>
#include <vector>

namespace nec {

// Options of segmentation: the clip lengths and caption noun, and the
// thresholds of the per-frame activities it cuts at.
struct SegmentOptions : KinematicOptions {
  double min_seconds = 2.0;            // shortest clip, e.g. 2 s
  double max_seconds = 6.0;            // longest clip, at least 2 × min_seconds, e.g. 6 s
  std::string creature = "dog";        // noun of the captions: "a dog trots forward"
  double min_phase_seconds = 0.5;      // shorter activities are absorbed by their neighbours

  // Throws std::invalid_argument naming the first bad field (these, then the thresholds).
  void validate() const;
};

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

// "a" or "an" before a noun of a caption, by its first letter ("an elephant", "a dog").
std::string indefinite_article(std::string_view noun);

}  // namespace nec
