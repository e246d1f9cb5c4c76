// Kinematic segmentation and captioning of long unlabelled takes.
#include "nec/corpus/segment.h"

#include "nec/motion/statistics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace nec {
namespace {

// How different two activities are, for choosing which neighbour absorbs a short run.
int distance(const Phase& a, const Phase& b) {
  const int gait = (a.activity == Activity::Jump || b.activity == Activity::Jump)
                       ? (a.activity == b.activity ? 0 : 1)
                       : std::abs(static_cast<int>(a.activity) - static_cast<int>(b.activity));
  return 2 * gait + std::abs(static_cast<int>(a.turn) - static_cast<int>(b.turn));
}

bool same_state(const Phase& a, const Phase& b) { return a.activity == b.activity && a.turn == b.turn; }

std::vector<Phase> runs_of(const KinematicSignals& s) {
  std::vector<Phase> runs;
  for (int t = 0; t < s.frame_count(); ++t) {
    if (!runs.empty() && runs.back().activity == s.activity[t] && runs.back().turn == s.turn[t]) {
      runs.back().end = t + 1;
    } else {
      runs.push_back({t, t + 1, s.activity[t], s.turn[t]});
    }
  }
  return runs;
}

void merge_equal_neighbours(std::vector<Phase>& runs) {
  std::vector<Phase> out;
  for (const Phase& run : runs) {
    if (!out.empty() && same_state(out.back(), run)) {
      out.back().end = run.end;
    } else {
      out.push_back(run);
    }
  }
  runs = std::move(out);
}

// Absorbs runs shorter than their minimum (jumps have their own) into the most
// similar neighbour, the longer one on a tie; shortest first.
void absorb_short_runs(std::vector<Phase>& runs, int min_frames, int min_jump_frames) {
  const auto minimum = [&](const Phase& p) { return p.activity == Activity::Jump ? min_jump_frames : min_frames; };
  while (runs.size() > 1) {
    int shortest = -1;
    for (int i = 0; i < static_cast<int>(runs.size()); ++i) {
      const int length = runs[i].end - runs[i].begin;
      if (length < minimum(runs[i]) && (shortest < 0 || length < runs[shortest].end - runs[shortest].begin))
        shortest = i;
    }
    if (shortest < 0) break;
    const int last = static_cast<int>(runs.size()) - 1;
    int into;
    if (shortest == 0) {
      into = 1;
    } else if (shortest == last) {
      into = last - 1;
    } else {
      const Phase& before = runs[shortest - 1];
      const Phase& after = runs[shortest + 1];
      const int d_before = distance(runs[shortest], before);
      const int d_after = distance(runs[shortest], after);
      if (d_before != d_after) {
        into = d_before < d_after ? shortest - 1 : shortest + 1;
      } else {
        into = (before.end - before.begin) >= (after.end - after.begin) ? shortest - 1 : shortest + 1;
      }
    }
    runs[shortest].activity = runs[into].activity;
    runs[shortest].turn = runs[into].turn;
    merge_equal_neighbours(runs);
  }
}

// The classification switches between lying or sitting and being up when the
// root crosses low_height; the change itself starts earlier. Moves such
// boundaries back to where the root left its previous level (at most 1.5 s),
// so that the whole "gets up" or "lies down" motion falls into the later phase.
void move_posture_boundaries(std::vector<Phase>& phases, const KinematicSignals& s) {
  const int max_shift = frames_in(1.5, s.fps);
  const int level_frames = frames_in(1.0, s.fps);
  constexpr double kLevelTolerance = 0.05;  // × standing height
  for (size_t i = 1; i < phases.size(); ++i) {
    Phase& before = phases[i - 1];
    Phase& after = phases[i];
    const bool rising = is_low(before.activity) && is_upright(after.activity);
    const bool falling = is_upright(before.activity) && is_low(after.activity);
    if (!rising && !falling) continue;
    const int change = after.begin;
    const int from = std::max(before.begin, change - level_frames);
    const double level = upper_median(std::vector<double>(s.height_ratio.begin() + from, s.height_ratio.begin() + change));
    const int limit = std::max(before.begin + 1, change - max_shift);
    int t = change;
    while (t > limit && (rising ? s.height_ratio[t - 1] > level + kLevelTolerance
                                : s.height_ratio[t - 1] < level - kLevelTolerance)) {
      --t;
    }
    before.end = t;
    after.begin = t;
  }
}

// A clip under construction: frames [begin, end).
struct Span {
  int begin;
  int end;
  int length() const { return end - begin; }
};

// The phase at frame `t` (phases cover the take in order).
const Phase& phase_at(const std::vector<Phase>& phases, int t) {
  const auto it =
      std::upper_bound(phases.begin(), phases.end(), t, [](int frame, const Phase& p) { return frame < p.end; });
  return *it;
}

std::vector<Span> cut_spans(const std::vector<Phase>& phases, int frame_count, int min_frames, int max_frames) {
  std::vector<Span> spans;
  for (const Phase& p : phases) spans.push_back({p.begin, p.end});
  // Merge spans shorter than the minimum, shortest first, into the neighbour
  // whose adjoining activity is most similar (the shorter one on a tie).
  while (spans.size() > 1) {
    int shortest = -1;
    for (int i = 0; i < static_cast<int>(spans.size()); ++i) {
      if (spans[i].length() < min_frames && (shortest < 0 || spans[i].length() < spans[shortest].length()))
        shortest = i;
    }
    if (shortest < 0) break;
    const int last = static_cast<int>(spans.size()) - 1;
    int into;
    if (shortest == 0) {
      into = 1;
    } else if (shortest == last) {
      into = last - 1;
    } else {
      const Span& s = spans[shortest];
      const int d_before = distance(phase_at(phases, s.begin), phase_at(phases, s.begin - 1));
      const int d_after = distance(phase_at(phases, s.end - 1), phase_at(phases, s.end));
      if (d_before != d_after) {
        into = d_before < d_after ? shortest - 1 : shortest + 1;
      } else {
        into = spans[shortest - 1].length() <= spans[shortest + 1].length() ? shortest - 1 : shortest + 1;
      }
    }
    const int low = std::min(shortest, into);
    spans[low] = {spans[low].begin, spans[low + 1].end};
    spans.erase(spans.begin() + low + 1);
  }
  // Split spans longer than the maximum into equal parts.
  std::vector<Span> out;
  for (const Span& s : spans) {
    const int parts = (s.length() + max_frames - 1) / max_frames;
    for (int k = 0; k < parts; ++k) {
      const int begin = s.begin + static_cast<int>(static_cast<long long>(s.length()) * k / parts);
      const int end = s.begin + static_cast<int>(static_cast<long long>(s.length()) * (k + 1) / parts);
      out.push_back({begin, end});
    }
  }
  if (out.empty() && frame_count > 0) out.push_back({0, frame_count});
  return out;
}

// ---------------------------------------------------------------------------
// Captions

// Where a travelling creature goes relative to where it faces.
enum class Direction { Forward, Backward, Left, Right, Unclear };

// Clearly forward or backward: the mean velocity along the facing is at least
// half the mean speed; sideways: the sideways part is also twice the forward one.
Direction travel_direction(const SegmentMeasurements& m) {
  if (m.forward_speed >= 0.5 * m.mean_speed) return Direction::Forward;
  if (m.forward_speed <= -0.5 * m.mean_speed) return Direction::Backward;
  if (std::abs(m.lateral_speed) >= 0.5 * m.mean_speed && std::abs(m.lateral_speed) > 2.0 * std::abs(m.forward_speed)) {
    return m.lateral_speed > 0 ? Direction::Left : Direction::Right;
  }
  return Direction::Unclear;
}

// Consecutive phases of one activity, as the caption describes them.
struct Group {
  int begin = 0;
  int end = 0;
  Activity activity = Activity::Stand;
  std::vector<Turn> turns;                   // turning sequence inside, e.g. {None, Left}; never empty
  std::array<int, 3> turn_frames{};          // frames turning right, straight, left
  bool jumps = false;                        // a jump happened during it (or ended it)
  int jump_direction = 0;                    // +1 onto a higher support, -1 down to a lower one, 0 same level
  bool still = false;                        // standing without moving the limbs
  bool circles = false;                      // turned 270 degrees or more in one direction
  Direction direction = Direction::Forward;  // of travel, relative to the facing
};

std::string side_word(Turn t) { return t == Turn::Left ? "left" : "right"; }

// Removes repeats and a straight stretch between two turns the same way: {L, None, L} -> {L}.
std::vector<Turn> collapse_turns(const std::vector<Turn>& turns) {
  std::vector<Turn> out;
  for (Turn t : turns) {
    if (!out.empty() && out.back() == t) continue;
    if (out.size() >= 2 && out.back() == Turn::None && out[out.size() - 2] == t) {
      out.pop_back();
      continue;
    }
    out.push_back(t);
  }
  return out;
}

// Verb phrase of a travelling group; `variant` in 0..2 picks a paraphrase.
// `brief`: another travelling group follows, so a straight one drops "forward".
std::string travel_phrase(const Group& g, int variant, bool brief) {
  const std::string verb = g.activity == Activity::Walk ? "walks" : g.activity == Activity::Trot ? "trots" : "runs";
  const std::string other = g.activity == Activity::Run ? "gallops" : verb;
  const auto& turns = g.turns;
  if (turns.size() == 1 && turns[0] == Turn::None) {
    if (g.direction == Direction::Left || g.direction == Direction::Right) {
      const std::string side = g.direction == Direction::Left ? "left" : "right";
      return variant == 2 ? "moves sideways to the " + side : verb + " sideways to the " + side;
    }
    if (g.direction == Direction::Backward) {
      return variant == 0 ? verb + " backward" : variant == 1 ? verb + " backwards" : "moves backward";
    }
    if (g.direction == Direction::Unclear)
      return variant == 0 ? verb + " around" : variant == 1 ? verb : other + " about";
    if (brief) return variant == 2 ? other : verb;
    return variant == 0 ? verb + " forward" : variant == 1 ? verb : other + " ahead";
  }
  if (turns.size() == 1) {
    const std::string side = side_word(turns[0]);
    if (g.circles) {
      return variant == 0   ? verb + " in a circle to the " + side
             : variant == 1 ? verb + " around in circles"
                            : other + " in a circle to the " + side;
    }
    return variant == 0   ? verb + " and turns " + side
           : variant == 1 ? verb + " while turning " + side
                          : other + " in a curve to the " + side;
  }
  if (turns.size() == 2 && turns[0] == Turn::None) {
    const std::string side = side_word(turns[1]);
    return variant == 0   ? verb + " forward, then turns " + side
           : variant == 1 ? verb + ", then turns " + side
                          : other + " ahead, then turns " + side;
  }
  if (turns.size() == 2 && turns[1] == Turn::None) {
    const std::string side = side_word(turns[0]);
    return variant == 0   ? verb + " and turns " + side + ", then goes straight"
           : variant == 1 ? verb + " while turning " + side + ", then straight on"
                          : other + " in a curve to the " + side + ", then straight";
  }
  if (turns.size() == 2) {
    return variant == 0   ? verb + " and turns " + side_word(turns[0]) + ", then " + side_word(turns[1])
           : variant == 1 ? verb + " while turning " + side_word(turns[0]) + ", then " + side_word(turns[1])
                          : other + ", turning " + side_word(turns[0]) + " then " + side_word(turns[1]);
  }
  return variant == 0   ? verb + ", turning left and right"
         : variant == 1 ? verb + " in a zigzag"
                        : other + ", weaving left and right";
}

// Verb phrase of a standing group.
std::string stand_phrase(const Group& g, const Group* previous, int variant) {
  const auto& turns = g.turns;
  const bool after_travel = previous && is_moving(previous->activity);
  if (turns.size() == 1 && turns[0] == Turn::None) {
    if (after_travel) {
      return g.still ? (variant == 0   ? "stops and stands still"
                        : variant == 1 ? "comes to a stop"
                                       : "stops and stays still")
                     : (variant == 0   ? "stops"
                        : variant == 1 ? "comes to a stop"
                                       : "stops moving");
    }
    return g.still ? (variant == 0   ? "stands still"
                      : variant == 1 ? "stands without moving"
                                     : "stays still")
                   : (variant == 0   ? "stands in place"
                      : variant == 1 ? "stands"
                                     : "stands on the spot");
  }
  std::string phrase;
  if (turns.size() == 1) {
    const std::string side = side_word(turns[0]);
    phrase = g.circles ? (variant == 0   ? "turns around to the " + side + " in place"
                          : variant == 1 ? "spins around to the " + side
                                         : "turns in a full circle to the " + side)
                       : (variant == 0   ? "turns " + side + " in place"
                          : variant == 1 ? "turns to the " + side + " on the spot"
                                         : "turns " + side + " while standing");
  } else if (turns.size() == 2 && turns[0] == Turn::None) {
    const std::string side = side_word(turns[1]);
    phrase = variant == 0   ? "stands, then turns " + side + " in place"
             : variant == 1 ? "stands, then turns to the " + side
                            : "stands, then turns " + side + " on the spot";
  } else if (turns.size() == 2 && turns[1] == Turn::None) {
    const std::string side = side_word(turns[0]);
    phrase = variant == 0   ? "turns " + side + " in place, then stands"
             : variant == 1 ? "turns to the " + side + ", then stands"
                            : "turns " + side + " on the spot, then stays there";
  } else {
    phrase = variant == 0   ? "turns left and right in place"
             : variant == 1 ? "turns from side to side"
                            : "turns left and right on the spot";
  }
  return after_travel ? "stops and " + phrase : phrase;
}

std::string group_phrase(const Group& g, const Group* previous, const Group* next, int variant) {
  const auto pick = [variant](const char* v0, const char* v1, const char* v2) {
    return std::string(variant == 0 ? v0 : variant == 1 ? v1 : v2);
  };
  const bool after_low = previous && (previous->activity == Activity::Lie || previous->activity == Activity::Sit);
  const bool from_lying = previous && previous->activity == Activity::Lie;
  std::string phrase;
  switch (g.activity) {
    case Activity::Lie:
      phrase = pick("lies down", "lies on the ground", "rests lying down");
      break;
    case Activity::Sit:
      phrase = from_lying ? pick("sits up", "sits up", "gets up into a sitting position")
               : previous ? pick("sits down", "sits down", "sits down on the ground")
                          : pick("sits", "sits on the ground", "sits still");
      break;
    case Activity::Jump:
      phrase = g.jump_direction > 0   ? pick("jumps up", "jumps up onto something", "leaps up onto a higher spot")
               : g.jump_direction < 0 ? pick("jumps down", "jumps down from a height", "leaps down")
                                      : pick("jumps", "leaps", "makes a jump");
      break;
    case Activity::Stand:
      if (after_low && g.turns.size() == 1 && g.turns[0] == Turn::None) {
        phrase = from_lying ? pick("gets up", "gets up", "gets back on its feet")
                            : pick("stands up", "stands up", "gets up from sitting");
      } else {
        phrase = stand_phrase(g, previous, variant);
        if (after_low) phrase = (from_lying ? "gets up and " : "stands up and ") + phrase;
      }
      break;
    case Activity::Walk:
    case Activity::Trot:
    case Activity::Run:
      phrase = travel_phrase(g, variant, next && is_moving(next->activity));
      if (after_low) phrase = (from_lying ? "gets up and " : "stands up and ") + phrase;
      break;
  }
  if (g.jumps && g.activity != Activity::Jump) {
    phrase += g.jump_direction > 0
                  ? pick(" and jumps up", " and jumps up onto something", " and leaps up onto a higher spot")
              : g.jump_direction < 0 ? pick(" and jumps down", " and jumps down from a height", " and leaps down")
                                     : pick(" and jumps", " and leaps", " and makes a jump");
  }
  return phrase;
}

std::vector<std::string> group_labels(const Group& g) {
  std::vector<std::string> labels;
  switch (g.activity) {
    case Activity::Lie:
      labels.push_back("lies down");
      break;
    case Activity::Sit:
      labels.push_back("sits");
      break;
    case Activity::Stand:
      labels.push_back(g.still && g.turns.size() == 1 && g.turns[0] == Turn::None ? "stands still" : "stands");
      break;
    case Activity::Walk:
      labels.push_back("walks");
      break;
    case Activity::Trot:
      labels.push_back("trots");
      break;
    case Activity::Run:
      labels.push_back("runs");
      break;
    case Activity::Jump:
      labels.push_back("jumps");
      break;
  }
  for (Turn t : g.turns) {
    if (t != Turn::None) labels.push_back("turns " + side_word(t));
  }
  if (g.jumps) labels.push_back("jumps");
  return labels;
}

// Groups worth describing: phases long enough to matter, jumps folded into
// their neighbours, consecutive phases of one activity joined, at most three.
std::vector<Group> describable_groups(const std::vector<Phase>& phases, const KinematicSignals& s,
                                      const SegmentOptions& o, int length) {
  const int keep_frames = std::max(frames_in(o.min_phase_seconds, s.fps), length / 7);
  std::vector<Phase> kept;
  std::vector<Phase> jumps;
  for (const Phase& p : phases) {
    if (p.activity == Activity::Jump) {
      jumps.push_back(p);
    } else if (p.end - p.begin >= keep_frames) {
      kept.push_back(p);
    }
  }
  if (kept.empty()) {
    kept.push_back(*std::max_element(phases.begin(), phases.end(),
                                     [](const Phase& a, const Phase& b) { return a.end - a.begin < b.end - b.begin; }));
    if (kept[0].activity == Activity::Jump) jumps.clear();
  }
  std::vector<Group> groups;
  for (const Phase& p : kept) {
    if (groups.empty() || groups.back().activity != p.activity) {
      Group g;
      g.begin = p.begin;
      g.activity = p.activity;
      groups.push_back(g);
    }
    groups.back().end = p.end;
    groups.back().turns.push_back(p.turn);
    groups.back().turn_frames[static_cast<int>(p.turn) + 1] += p.end - p.begin;
  }
  // A jump belongs to the activity it interrupts or ends: the last group that began before it.
  for (const Phase& jump : jumps) {
    size_t owner = 0;
    for (size_t i = 0; i < groups.size(); ++i) {
      if (groups[i].begin <= jump.begin) owner = i;
    }
    // Support level change across the jump, in standing heights; mixed directions say just "jumps".
    const double before = s.floor_height[std::max(0, jump.begin - 1)];
    const double after = s.floor_height[std::min(s.frame_count() - 1, jump.end)];
    const double change = (after - before) / s.standing_height;
    const int direction = change > o.airborne_height ? 1 : change < -o.airborne_height ? -1 : 0;
    Group& g = groups[owner];
    g.jump_direction = !g.jumps || g.jump_direction == direction ? direction : 0;
    g.jumps = true;
  }
  while (groups.size() > 3) {  // drop the shortest, then rejoin equal neighbours
    const auto shortest = std::min_element(
        groups.begin(), groups.end(), [](const Group& a, const Group& b) { return a.end - a.begin < b.end - b.begin; });
    groups.erase(shortest);
    std::vector<Group> joined;
    for (const Group& g : groups) {
      if (!joined.empty() && joined.back().activity == g.activity) {
        joined.back().end = g.end;
        joined.back().turns.insert(joined.back().turns.end(), g.turns.begin(), g.turns.end());
        for (int k = 0; k < 3; ++k) joined.back().turn_frames[k] += g.turn_frames[k];
        joined.back().jumps = joined.back().jumps || g.jumps;
      } else {
        joined.push_back(g);
      }
    }
    groups = std::move(joined);
  }
  for (Group& g : groups) {
    // One activity: its turns in order; several: each with its main turning only.
    if (groups.size() == 1) {
      g.turns = collapse_turns(g.turns);
    } else {
      const auto& f = g.turn_frames;  // right, straight, left; straight wins ties
      g.turns = {f[0] > std::max(f[1], f[2]) ? Turn::Right : f[2] > std::max(f[0], f[1]) ? Turn::Left : Turn::None};
    }
    const SegmentMeasurements m = measure_segment(s, g.begin, g.end);
    g.still = m.joint_speed < o.still_joint_speed;
    g.circles = g.turns.size() == 1 && g.turns[0] != Turn::None && std::abs(m.heading_change) >= 270.0;
    if (is_moving(g.activity)) {
      g.direction = travel_direction(m);
    }
  }
  return groups;
}

// `before`: the posture the segment starts from when it begins with a change
// between lying or sitting and being up ("gets up and ...", "sits down"); null otherwise.
void describe(Segment& segment, const KinematicSignals& s, const SegmentOptions& o, const Group* before) {
  const std::vector<Group> groups = describable_groups(segment.phases, s, o, segment.end - segment.begin);
  const std::string subject = indefinite_article(o.creature) + " " + o.creature;
  for (int variant = 0; variant < 3; ++variant) {
    std::string caption = subject;
    for (size_t i = 0; i < groups.size(); ++i) {
      caption += i == 0 ? " " : (i + 1 == groups.size()) ? ", then " : ", ";
      caption += group_phrase(groups[i], i > 0 ? &groups[i - 1] : before,
                              i + 1 < groups.size() ? &groups[i + 1] : nullptr, variant);
    }
    if (std::find(segment.captions.begin(), segment.captions.end(), caption) == segment.captions.end()) {
      segment.captions.push_back(caption);
    }
  }
  for (const Group& g : groups) {
    for (const std::string& label : group_labels(g)) {
      if (std::find(segment.labels.begin(), segment.labels.end(), label) == segment.labels.end()) {
        segment.labels.push_back(label);
      }
    }
  }
}

}  // namespace

void SegmentOptions::validate() const {
  const auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("SegmentOptions: ") + what);
  };
  require(min_seconds > 0.0, "min_seconds must be positive");
  require(max_seconds >= 2.0 * min_seconds, "max_seconds must be at least 2 × min_seconds");
  require(!creature.empty(), "creature must not be empty");
  require(min_phase_seconds > 0.0, "min_phase_seconds must be positive");
  KinematicOptions::validate();
}

SegmentMeasurements measure_segment(const KinematicSignals& s, int begin, int end) {
  SegmentMeasurements m;
  begin = std::clamp(begin, 0, s.frame_count());
  end = std::clamp(end, begin, s.frame_count());
  if (end == begin) return m;
  const int n = end - begin;
  const auto mean = [&](const std::vector<double>& v) {
    return std::accumulate(v.begin() + begin, v.begin() + end, 0.0) / n;
  };
  const auto range = [&](const std::vector<double>& v) {
    return std::vector<double>(v.begin() + begin, v.begin() + end);
  };
  m.seconds = n / s.fps;
  m.mean_speed = mean(s.speed);
  m.max_speed = *std::max_element(s.speed.begin() + begin, s.speed.begin() + end);
  m.forward_speed = mean(s.forward_speed);
  m.lateral_speed = mean(s.lateral_speed);
  m.heading_change = s.heading[end - 1] - s.heading[begin];
  m.turn_rate = n > 1 ? m.heading_change * s.fps / (n - 1) : 0.0;
  m.height_ratio = upper_median(range(s.height_ratio));
  m.min_height_ratio = *std::min_element(s.height_ratio.begin() + begin, s.height_ratio.begin() + end);
  m.trunk_pitch = upper_median(range(s.trunk_pitch));
  m.max_rise = *std::max_element(s.rise.begin() + begin, s.rise.begin() + end);
  m.max_vertical_speed = *std::max_element(s.vertical_speed.begin() + begin, s.vertical_speed.begin() + end);
  m.joint_speed = mean(s.joint_speed);
  return m;
}

TakeSegmentation segment_take(const Clip& take, const SegmentOptions& options) {
  options.validate();
  TakeSegmentation result;
  result.signals = measure_kinematics(take, options);
  const KinematicSignals& s = result.signals;
  const int frame_count = s.frame_count();
  if (frame_count == 0) return result;

  result.phases = runs_of(s);
  absorb_short_runs(result.phases, frames_in(options.min_phase_seconds, s.fps),
                    frames_in(options.min_jump_seconds, s.fps));
  move_posture_boundaries(result.phases, s);

  const std::vector<Span> spans = cut_spans(result.phases, frame_count, frames_in(options.min_seconds, s.fps),
                                            frames_in(options.max_seconds, s.fps));
  for (const Span& span : spans) {
    Segment segment;
    segment.begin = span.begin;
    segment.end = span.end;
    for (const Phase& p : result.phases) {
      if (p.end <= span.begin || p.begin >= span.end) continue;
      segment.phases.push_back({std::max(p.begin, span.begin), std::min(p.end, span.end), p.activity, p.turn});
    }
    const auto longest =
        std::max_element(segment.phases.begin(), segment.phases.end(),
                         [](const Phase& a, const Phase& b) { return a.end - a.begin < b.end - b.begin; });
    segment.activity = longest->activity;
    segment.jumps = std::any_of(segment.phases.begin(), segment.phases.end(),
                                [](const Phase& p) { return p.activity == Activity::Jump; });
    segment.measurements = measure_segment(s, span.begin, span.end);
    const double rate = segment.measurements.turn_rate;
    segment.turn = std::abs(rate) < options.turn_rate ? Turn::None : rate > 0 ? Turn::Left : Turn::Right;
    // A segment that starts where the posture changes describes the change.
    const auto first =
        std::find_if(result.phases.begin(), result.phases.end(), [&](const Phase& p) { return p.end > span.begin; });
    Group before;
    bool posture_change = false;
    if (first != result.phases.begin() && first->begin == span.begin) {
      before.activity = std::prev(first)->activity;
      posture_change = (is_low(before.activity) && is_upright(first->activity)) ||
                       (is_upright(before.activity) && is_low(first->activity));
    }
    describe(segment, s, options, posture_change ? &before : nullptr);
    result.segments.push_back(std::move(segment));
  }
  return result;
}

std::string indefinite_article(std::string_view noun) {
  if (noun.empty()) return "a";
  const char c = static_cast<char>(std::tolower(static_cast<unsigned char>(noun[0])));
  return (c == 'a' || c == 'e' || c == 'i' || c == 'o' || c == 'u') ? "an" : "a";
}

}  // namespace nec
