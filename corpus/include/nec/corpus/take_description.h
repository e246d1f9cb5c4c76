// A take's free-text description read into captions of the clips the segmenter cuts it into.
//
//   TakeDescription d = parse_take_description("jumping jacks, side twists, squats, jog");
//   // d.parts: "does jumping jacks" (in place), "does side twists", "does squats", "jogs" (travel)
//   std::vector<std::string> captions = described_clip_captions(d, segment, "person", /*whole_take=*/false);
//   // a clip the segmenter saw jog: {"a person jogs", "the person jogs"}
//
// Descriptions are what motion databases ship beside long takes (CMU's "soccer - kick ball", "sit on
// stepstool, stand up", "dance - small jetes, pirouette"): an optional theme before " - ", then parts
// separated by commas, each a verb phrase ("climb ladder"), a noun phrase ("forward jump", "jumping jacks")
// or a detail of the previous part ("ankle on other knee"); "run/jog" gives alternatives. Each part becomes a
// third-person verb phrase and gets the kind of activity it names, which is what matches it to clips:
//   travel  (walk, stride, jog, run, sprint, navigate, dribble or step with a direction)
//           agrees with a clip that walks, trots or runs a third of its time or more;
//   jump    (jump, hop, leap, jete) agrees with a clip where the segmenter saw a jump;
//   low     (sit, lie, lower, squat down; stand up, rise, get up) agrees with a clip that sits or lies;
//   in place (everything else: gestures, dance figures, drinking, boxing) agrees with a clip that travels
//           less than half its time, or with every clip when the description names no travel.
// A clip gets the description's parts that agree with it, in the description's order; a take that is one clip
// gets them all. The theme alone ("a person plays basketball") is true of every clip of the take.
#pragma once

#include "nec/corpus/segment.h"

#include <string>
#include <string_view>
#include <vector>

namespace nec {

enum class DescribedKind { Travel, Jump, Low, InPlace };

struct DescribedPart {
  std::string text;                  // as written, lower case, e.g. "forward jump"
  std::vector<std::string> phrases;  // third-person verb phrases, canonical first, e.g. {"jumps forward"}
  DescribedKind kind = DescribedKind::InPlace;
};

struct TakeDescription {
  std::string text;                 // the whole description as written
  std::string theme;                // e.g. "basketball", "" when none
  std::vector<DescribedPart> parts;  // in the description's order; details ("with hand on chin") joined to theirs
};

// Throws std::invalid_argument for a description without words.
TakeDescription parse_take_description(std::string_view text);

// Whether a clip's kinematics agree with a part (the rules above).
bool part_agrees(const TakeDescription& description, const DescribedPart& part, const Segment& clip);

// Captions of one clip cut from a described take, canonical first: the agreeing parts said with the noun
// ("a person jogs", "the person jogs", "a person plays basketball and dribbles forward"), else the theme alone;
// {} when neither. `whole_take`: the clip is the whole take, so every part agrees.
std::vector<std::string> described_clip_captions(const TakeDescription& description, const Segment& clip,
                                                 std::string_view noun, bool whole_take);

}  // namespace nec
