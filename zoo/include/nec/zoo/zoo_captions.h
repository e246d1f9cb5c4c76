// Multi-level captions of zoo clips, as in How to Move Your Dragon section
// 4.3: short (the high-level action), mid (+ speed, direction, turning) and
// long (+ initial posture and part-level detail). They are derived from the
// creature and the MotionSpec that made the clip, so they are true by
// construction; the phrasing is drawn from a vocabulary by a seed, so a
// corpus of captions is not one template.
//
//   SynthesizedMotion out = synthesize_motion(spider, spec);
//   Captions c = caption_motion(spider, out.spec, /*phrasing_seed=*/7);
//   // c.short_text  "a spider walks"
//   // c.mid_text    "a spider walks forward quickly, turning left"
//   // c.long_text   "starting still, a spider walks forward quickly, moving its legs in waves
//   //                from back to front, while turning left"
//
// Pass the spec the synthesizer returns (SynthesizedMotion::spec): it holds
// the speed and turn rate that were actually made.
#pragma once

#include "nec/zoo/motion_synthesis.h"

#include <cstdint>
#include <string>
#include <vector>

namespace nec::zoo {

struct Captions {
  std::string short_text;  // e.g. "a dog trots"
  std::string mid_text;    // e.g. "a dog trots forward slowly, veering right"
  std::string long_text;   // e.g. "from a standstill, a dog trots forward slowly, moving diagonal legs together, ..."

  // The three captions, short first: the lines of a `clip.txt` sidecar.
  std::vector<std::string> lines() const { return {short_text, mid_text, long_text}; }
};

// How a locomotion clip turns, from its turn rate and total heading change.
enum class TurnClass {
  Straight,  // |turn rate| below kVeerDegreesPerSecond: no turn is mentioned
  Veer,      // a gentle curve: "veering left"
  Turn,      // |turn rate| of kTurnDegreesPerSecond or more: "turning left"
  Circle,    // the heading changes by kCircleDegrees or more over the clip: "in a circle to the left"
};
constexpr double kVeerDegreesPerSecond = 8.0;
constexpr double kTurnDegreesPerSecond = 35.0;
constexpr double kCircleDegrees = 330.0;
TurnClass classify_turn(const MotionSpec& spec);

// Throws std::invalid_argument when the plan does not support the action.
Captions caption_motion(const Creature& creature, const MotionSpec& spec, uint64_t phrasing_seed);

}  // namespace nec::zoo
