// Multi-level captions of zoo clips from the creature and the motion spec,
// with a vocabulary of phrasings per action, speed, turn and body plan.
#include "nec/zoo/zoo_captions.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace nec::zoo {
namespace {

// A verb phrase in the two forms the templates need: "walks" / "walking".
struct Verb {
  std::string finite;
  std::string participle;
};

// Picks phrasings deterministically from the phrasing seed.
class Phraser {
 public:
  explicit Phraser(uint64_t seed) : random_(mix_seed(seed, 0xCA9710)) {}
  template <typename T>
  const T& pick(const std::vector<T>& options) {
    return options.at(static_cast<size_t>(random_.below(static_cast<int>(options.size()))));
  }
  bool chance(double probability) { return random_.chance(probability); }

 private:
  SplitMix64 random_;
};

bool starts_with_vowel_sound(const std::string& word) {
  return !word.empty() && std::string("aeiou").find(word[0]) != std::string::npos;
}

std::string noun_phrase(const Creature& creature) {
  const std::string species = creature.species.empty() ? std::string(body_plan_name(creature.plan)) : creature.species;
  return (starts_with_vowel_sound(species) ? "an " : "a ") + species;
}

// What people call a creature when they do not name it: "someone", "an animal", "a creature".
std::vector<std::string> generic_nouns(const Creature& creature) {
  switch (moves_like(creature.plan)) {
    case BodyPlan::Biped: return {"someone", "a figure", "a character"};
    case BodyPlan::Quadruped:
      if (creature.plan == BodyPlan::Primate) return {"an ape", "an animal"};
      return {"an animal", "a four-legged animal"};
    case BodyPlan::Bird: return creature.plan == BodyPlan::Dinosaur ? std::vector<std::string>{"a creature", "a reptile"}
                                : creature.plan == BodyPlan::Hopper  ? std::vector<std::string>{"an animal", "a creature"}
                                                                     : std::vector<std::string>{"a bird", "an animal"};
    case BodyPlan::Snake: return {"a reptile", "a creature"};
    case BodyPlan::Fish: return {"a sea creature", "a creature"};
    case BodyPlan::Dragon: return {"a creature", "a monster"};
    default: return {"a creature", "a critter", "a many-legged creature"};
  }
}

int count_limbs(const Creature& creature, LimbKind kind) {
  int count = 0;
  for (const Limb& limb : creature.limbs) count += limb.kind == kind ? 1 : 0;
  return count;
}

bool has_limb(const Creature& creature, LimbKind kind) { return count_limbs(creature, kind) > 0; }

std::string number_word(int n) {
  static const char* const words[] = {"no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten"};
  return n >= 0 && n <= 10 ? words[n] : std::to_string(n);
}

std::string side_word(Side side) { return side == Side::Right ? "right" : "left"; }

bool is_arthropod(BodyPlan plan) {
  return plan == BodyPlan::Hexapod || plan == BodyPlan::Spider || plan == BodyPlan::Centipede;
}
bool is_four_legged(BodyPlan plan) { return plan == BodyPlan::Quadruped || plan == BodyPlan::Dragon; }
// Plant eaters, which graze.
bool is_grazer(const Creature& creature) {
  return creature.plan == BodyPlan::Ungulate || creature.species == "horse";
}

// Where a walk goes relative to the creature's facing (MotionSpec::direction).
enum class Heading { Forward, Backward, Left, Right };

Heading travel_heading(const MotionSpec& spec) {
  const double d = spec.direction;
  if (std::abs(d) > 135.0) return Heading::Backward;
  if (d > 45.0) return Heading::Left;
  if (d < -45.0) return Heading::Right;
  return Heading::Forward;
}

// ---- verbs -----------------------------------------------------------------

std::vector<Verb> action_verbs(const Creature& creature, const MotionSpec& spec, SpeedClass speed) {
  const BodyPlan own = creature.plan;
  const BodyPlan plan = moves_like(own);  // a crab is worded as the spider it moves like, unless said otherwise
  const bool slow = speed == SpeedClass::Slow;
  const bool fast = speed == SpeedClass::Fast;
  std::vector<Verb> verbs;
  switch (spec.action) {
    case Action::Walk:
      if (travel_heading(spec) == Heading::Backward) {
        verbs = {{"walks", "walking"}, {"backs up", "backing up"}, {"steps back", "stepping back"},
                 {"backs away", "backing away"}};
        break;
      }
      if (travel_heading(spec) != Heading::Forward) {
        const std::string d = travel_heading(spec) == Heading::Left ? "left" : "right";
        verbs = {{"walks", "walking"}, {"sidesteps", "sidestepping"}, {"steps sideways to the " + d,
                 "stepping sideways to the " + d}, {"shuffles sideways to the " + d, "shuffling sideways to the " + d}};
        if (is_arthropod(plan)) verbs.push_back({"scuttles sideways to the " + d, "scuttling sideways to the " + d});
        break;
      }
      if (own == BodyPlan::Hopper) {
        verbs = {{"hops", "hopping"}, {"hops along", "hopping along"}, {"moves in small hops", "moving in small hops"}};
        break;
      }
      verbs = {{"walks", "walking"}};
      if (is_arthropod(plan)) {
        verbs.push_back({"crawls", "crawling"});
        if (!slow) verbs.push_back({"scuttles", "scuttling"});
      }
      if (plan == BodyPlan::Biped && slow) verbs.push_back({"strolls", "strolling"});
      if (plan == BodyPlan::Biped && !slow) verbs.push_back({"strides", "striding"});
      if (is_four_legged(plan) && slow) verbs.push_back({"plods", "plodding"});
      if ((is_four_legged(plan) || plan == BodyPlan::Biped) && slow) verbs.push_back({"ambles", "ambling"});
      if (own == BodyPlan::Bird || own == BodyPlan::GroundBird) verbs.push_back({"struts", "strutting"});
      if (own == BodyPlan::Primate) {
        verbs.push_back({"knuckle-walks", "knuckle-walking"});
        verbs.push_back({"walks on its knuckles", "walking on its knuckles"});
      }
      if (own == BodyPlan::Dinosaur) verbs.push_back({"stomps", "stomping"});
      if ((own == BodyPlan::Dinosaur || own == BodyPlan::Elephant) && slow) verbs.push_back({"lumbers", "lumbering"});
      break;
    case Action::Trot:
      if (own == BodyPlan::Elephant) {
        verbs = {{"hurries along", "hurrying along"}, {"walks briskly", "walking briskly"}, {"trots", "trotting"}};
        break;
      }
      verbs = {{"trots", "trotting"}, {"jogs", "jogging"}, {"moves at a trot", "moving at a trot"}};
      break;
    case Action::Run:
      if (own == BodyPlan::Hopper) {
        verbs = {{"bounds along", "bounding along"}, {"hops", "hopping"}, {"races along in big hops", "racing along in big hops"}};
        break;
      }
      verbs = {{"runs", "running"}};
      if (fast) {
        verbs.push_back({"sprints", "sprinting"});
        verbs.push_back({"dashes", "dashing"});
        verbs.push_back({"races", "racing"});
      }
      if (is_arthropod(plan) && fast) {
        verbs.push_back({"scurries", "scurrying"});
        verbs.push_back({"skitters", "skittering"});
      }
      break;
    case Action::Gallop:
      if (own == BodyPlan::Primate) {
        verbs = {{"runs on all fours", "running on all fours"}, {"charges", "charging"}, {"bounds", "bounding"}};
        break;
      }
      verbs = {{"gallops", "galloping"}, {"runs at a gallop", "running at a gallop"}, {"bounds", "bounding"}};
      break;
    case Action::Turn:
      verbs = {{"turns on the spot", "turning on the spot"},
               {"turns in place", "turning in place"},
               {"pivots in place", "pivoting in place"}};
      break;
    case Action::Idle:
      if (plan == BodyPlan::Fish) {
        verbs = {{"hovers", "hovering"}, {"floats in place", "floating in place"}, {"idles in the water", "idling in the water"}};
      } else if (plan == BodyPlan::Snake) {
        verbs = {{"lies still", "lying still"}, {"rests on the ground", "resting on the ground"}, {"idles", "idling"}};
      } else {
        verbs = {{"stands still", "standing still"}, {"stands in place", "standing in place"}, {"idles", "idling"},
                 {"waits", "waiting"}};
      }
      break;
    case Action::Jump:
      verbs = {{"jumps", "jumping"}, {"leaps", "leaping"}};
      if (plan == BodyPlan::Bird || plan == BodyPlan::Spider || plan == BodyPlan::Hexapod) verbs.push_back({"hops", "hopping"});
      break;
    case Action::Sit:
      if (plan == BodyPlan::Biped) {
        verbs = {{"sits down", "sitting down"},
                 {"sits down on the ground", "sitting down on the ground"},
                 {"takes a seat on the ground", "taking a seat on the ground"}};
      } else if (own == BodyPlan::Hopper) {
        verbs = {{"sits down", "sitting down"}, {"sits back on its tail", "sitting back on its tail"},
                 {"settles down", "settling down"}};
      } else if (plan == BodyPlan::Bird) {
        verbs = {{"sits down", "sitting down"}, {"settles down", "settling down"}, {"hunkers down", "hunkering down"}};
      } else {
        verbs = {{"sits down", "sitting down"}, {"sits", "sitting"}, {"sits back on its haunches", "sitting back on its haunches"}};
      }
      break;
    case Action::LieDown:
      if (is_arthropod(plan)) {
        verbs = {{"lowers its body to the ground", "lowering its body to the ground"},
                 {"crouches flat", "crouching flat"},
                 {"settles onto the ground", "settling onto the ground"}};
      } else {
        verbs = {{"lies down", "lying down"},
                 {"settles onto the ground", "settling onto the ground"},
                 {"lowers itself to the ground", "lowering itself to the ground"}};
      }
      break;
    case Action::Attack:
      if (own == BodyPlan::Crab) {
        verbs = {{"snaps its claws", "snapping its claws"}, {"raises its claws", "raising its claws"},
                 {"threatens with its claws", "threatening with its claws"}};
        break;
      }
      if (own == BodyPlan::Elephant) {
        verbs = {{"raises its trunk and trumpets", "raising its trunk and trumpeting"}, {"trumpets", "trumpeting"},
                 {"lunges with its trunk raised", "lunging with its trunk raised"}};
        break;
      }
      if (own == BodyPlan::Primate) {
        verbs = {{"lunges", "lunging"}, {"attacks", "attacking"}, {"swipes at something", "swiping at something"}};
        break;
      }
      switch (own == BodyPlan::Dinosaur ? own : plan) {  // a dinosaur bites, it does not peck
        case BodyPlan::Biped:
          verbs = {{"punches", "punching"}, {"throws a punch", "throwing a punch"}, {"strikes", "striking"}};
          break;
        case BodyPlan::Hexapod:
        case BodyPlan::Spider:
          verbs = {{"rears up and strikes", "rearing up and striking"},
                   {"attacks with its front legs", "attacking with its front legs"},
                   {"strikes", "striking"}};
          break;
        case BodyPlan::Snake:
          verbs = {{"strikes", "striking"}, {"lunges", "lunging"}, {"attacks", "attacking"}};
          break;
        case BodyPlan::Fish:
          verbs = {{"darts forward to bite", "darting forward to bite"}, {"lunges", "lunging"}, {"attacks", "attacking"}};
          break;
        case BodyPlan::Bird:
          verbs = {{"pecks", "pecking"}, {"pecks at the ground", "pecking at the ground"}};
          break;
        case BodyPlan::Centipede:
          verbs = {{"strikes with its head", "striking with its head"}, {"attacks", "attacking"}};
          break;
        default:
          verbs = {{"lunges and bites", "lunging and biting"}, {"attacks", "attacking"}, {"snaps forward", "snapping forward"}};
          break;
      }
      break;
    case Action::Slither:
      verbs = {{"slithers", "slithering"}, {"crawls", "crawling"}, {"undulates along", "undulating along"}};
      break;
    case Action::Swim:
      verbs = {{"swims", "swimming"}, {"cruises", "cruising"}};
      break;
    case Action::Fly:
      verbs = {{"flies", "flying"}, {"flaps through the air", "flapping through the air"}, {"flies on beating wings", "flying on beating wings"}};
      break;
    case Action::Glide:
      verbs = {{"glides", "gliding"}, {"soars", "soaring"}, {"sails through the air", "sailing through the air"}};
      break;
    case Action::TakeOff:
      verbs = {{"takes off", "taking off"}, {"lifts off", "lifting off"}, {"takes flight", "taking flight"},
               {"launches into the air", "launching into the air"}};
      break;
    case Action::FlapWings:
      verbs = {{"flaps its wings", "flapping its wings"}, {"beats its wings", "beating its wings"}};
      break;
    case Action::Wave:
      verbs = {{"waves", "waving"}, {"waves hello", "waving hello"}, {"waves goodbye", "waving goodbye"}};
      break;
    case Action::RaiseHands:
      if (spec.side == Side::None) {
        verbs = {{"raises its hands", "raising its hands"}, {"puts its hands up", "putting its hands up"},
                 {"lifts its arms", "lifting its arms"}};
      } else {
        verbs = {{"raises a hand", "raising a hand"}, {"puts a hand up", "putting a hand up"},
                 {"lifts an arm", "lifting an arm"}};
      }
      break;
    case Action::Point:
      verbs = {{"points", "pointing"}, {"points ahead", "pointing ahead"}, {"points forward", "pointing forward"}};
      break;
    case Action::Clap:
      verbs = {{"claps", "clapping"}, {"claps its hands", "clapping its hands"}, {"applauds", "applauding"}};
      break;
    case Action::Bow:
      verbs = {{"bows", "bowing"}, {"takes a bow", "taking a bow"}, {"bows down", "bowing down"}};
      break;
    case Action::Crouch:
      verbs = {{"crouches", "crouching"}, {"crouches down", "crouching down"}, {"squats down", "squatting down"},
               {"ducks down", "ducking down"}};
      break;
    case Action::Kick:
      verbs = {{"kicks", "kicking"}, {"throws a kick", "throwing a kick"}, {"kicks forward", "kicking forward"}};
      break;
    case Action::Shake:
      if (plan == BodyPlan::Bird) {
        verbs = {{"shakes its feathers", "shaking its feathers"}, {"ruffles its feathers", "ruffling its feathers"},
                 {"shakes itself", "shaking itself"}};
      } else {
        verbs = {{"shakes itself", "shaking itself"}, {"shakes itself off", "shaking itself off"},
                 {"shakes off water", "shaking off water"}, {"shakes its body", "shaking its body"}};
      }
      break;
    case Action::JumpingJacks:
      verbs = {{"does jumping jacks", "doing jumping jacks"}, {"does star jumps", "doing star jumps"},
               {"does a set of jumping jacks", "doing a set of jumping jacks"}};
      break;
    case Action::Stretch:
      verbs = {{"stretches", "stretching"}, {"stretches its arms over its head", "stretching its arms over its head"},
               {"reaches up and stretches", "reaching up and stretching"}};
      break;
    case Action::Dance:
      verbs = {{"dances", "dancing"}, {"dances in place", "dancing in place"}, {"grooves to the music", "grooving to the music"},
               {"sways to the beat", "swaying to the beat"}};
      break;
    case Action::GetUp:
      if (is_arthropod(plan)) {
        verbs = {{"rises from the ground", "rising from the ground"},
                 {"lifts its body off the ground", "lifting its body off the ground"},
                 {"stands back up", "standing back up"}};
      } else {
        verbs = {{"gets up", "getting up"}, {"stands up", "standing up"}, {"rises to its feet", "rising to its feet"},
                 {"gets back on its feet", "getting back on its feet"}};
      }
      break;
    case Action::Eat:
      verbs = {{"eats", "eating"}, {"feeds", "feeding"}, {"lowers its head to eat", "lowering its head to eat"},
               {"drinks", "drinking"}};
      if (is_grazer(creature)) {
        verbs.push_back({"grazes", "grazing"});
        verbs.push_back({"crops the grass", "cropping the grass"});
      } else {
        verbs.push_back({"sniffs the ground", "sniffing the ground"});
      }
      break;
  }
  return verbs;
}

// ---- modifiers -------------------------------------------------------------

// The manner as an adjective of the subject ("a tired dog"), "" when neutral.
std::string manner_adjective(Manner manner, Phraser& phraser) {
  switch (manner) {
    case Manner::Tired: return phraser.pick<std::string>({"tired", "weary", "exhausted"});
    case Manner::Energetic: return phraser.pick<std::string>({"energetic", "lively", "spirited"});
    case Manner::Cautious: return phraser.pick<std::string>({"cautious", "wary", "nervous"});
    case Manner::Proud: return phraser.pick<std::string>({"proud", "confident", "haughty"});
    case Manner::Neutral: break;
  }
  return "";
}

// The manner as an adverbial after the predicate ("wearily"), "" when neutral; some only of a creature that moves.
std::string manner_adverbial(Manner manner, bool moves, Phraser& phraser) {
  switch (manner) {
    case Manner::Tired:
      return moves ? phraser.pick<std::string>({"wearily", "tiredly", "sluggishly", "as if exhausted"})
                   : phraser.pick<std::string>({"wearily", "tiredly", "as if exhausted"});
    case Manner::Energetic:
      return moves ? phraser.pick<std::string>({"energetically", "with a spring in its step", "full of energy",
                                                "briskly"})
                   : phraser.pick<std::string>({"energetically", "full of energy"});
    case Manner::Cautious: return phraser.pick<std::string>({"cautiously", "carefully", "warily"});
    case Manner::Proud: return phraser.pick<std::string>({"proudly", "confidently", "with its chest out"});
    case Manner::Neutral: break;
  }
  return "";
}

// What the manner does to the body, for the long caption.
std::string manner_detail(Manner manner, Phraser& phraser) {
  switch (manner) {
    case Manner::Tired: return phraser.pick<std::string>({"its head hanging low", "its shoulders slumped"});
    case Manner::Energetic: return phraser.pick<std::string>({"bouncing with each step", "lifting its feet high"});
    case Manner::Cautious: return phraser.pick<std::string>({"keeping its body low", "looking around as it goes"});
    case Manner::Proud: return phraser.pick<std::string>({"its head up", "its chest lifted"});
    case Manner::Neutral: break;
  }
  return "";
}

std::string speed_words(SpeedClass speed, Phraser& phraser) {
  switch (speed) {
    case SpeedClass::Slow: return phraser.pick<std::string>({"slowly", "at a slow pace", "leisurely", "unhurriedly"});
    case SpeedClass::Fast: return phraser.pick<std::string>({"quickly", "fast", "rapidly", "at a fast pace", "at high speed"});
    case SpeedClass::Normal: return phraser.pick<std::string>({"", "", "at a steady pace", "at a moderate pace"});
  }
  return "";
}

// Participial turn clause for travelling clips, e.g. "veering left"; "" when straight.
std::string turn_participle(const MotionSpec& spec, Phraser& phraser, bool long_form) {
  const std::string d = side_word(spec.turn_rate > 0.0 ? Side::Left : Side::Right);
  switch (classify_turn(spec)) {
    case TurnClass::Straight: return "";
    case TurnClass::Veer:
      return phraser.pick<std::string>({"veering " + d, "curving to the " + d, "bearing " + d, "drifting to the " + d});
    case TurnClass::Turn:
      return long_form ? phraser.pick<std::string>({"while turning " + d, "turning " + d, "turning to the " + d,
                                                    "making a " + d + " turn"})
                       : phraser.pick<std::string>({"turning " + d, "turning to the " + d});
    case TurnClass::Circle:
      return phraser.pick<std::string>({"in a circle to the " + d, "circling to the " + d, "going around in a circle to the " + d});
  }
  return "";
}

// Where a travelling clip goes: "forward" or, without turning, "straight ahead"; "backward", "to the left".
std::string direction_words(const MotionSpec& spec, Phraser& phraser) {
  switch (travel_heading(spec)) {
    case Heading::Backward: return phraser.pick<std::string>({"backward", "backwards", "in reverse"});
    case Heading::Left: return phraser.pick<std::string>({"to the left", "sideways to the left", "leftward"});
    case Heading::Right: return phraser.pick<std::string>({"to the right", "sideways to the right", "rightward"});
    case Heading::Forward: break;
  }
  if (spec.action == Action::Slither) return phraser.pick<std::string>({"forward", "along the ground", "ahead"});
  if (spec.action == Action::Fly || spec.action == Action::Glide) return phraser.pick<std::string>({"forward", "ahead", "through the air"});
  if (classify_turn(spec) == TurnClass::Straight) return phraser.pick<std::string>({"forward", "ahead", "straight ahead"});
  return phraser.pick<std::string>({"forward", "ahead"});
}

// Turning on the spot: how far and which way.
std::string turn_in_place_words(const MotionSpec& spec, Phraser& phraser) {
  const double total = std::abs(heading_change_degrees(spec));
  const std::string d = side_word(spec.turn_rate > 0.0 ? Side::Left : Side::Right);
  if (total >= kCircleDegrees) return phraser.pick<std::string>({"spins a full circle to the " + d, "turns all the way around to the " + d});
  if (total >= 150.0) return phraser.pick<std::string>({"turns around to the " + d, "turns about to the " + d});
  return phraser.pick<std::string>({"turns " + d + " on the spot", "turns to the " + d + " in place", "pivots to the " + d});
}

std::string initial_posture(const Creature& creature, const MotionSpec& spec, Phraser& phraser) {
  const BodyPlan plan = creature.plan;
  const int legs = count_limbs(creature, LimbKind::Leg);
  if (spec.action == Action::Fly) return phraser.pick<std::string>({"already in the air", "in flight", "up in the air"});
  if (spec.action == Action::Glide) return phraser.pick<std::string>({"already airborne", "up in the air"});
  if (is_locomotion(spec.action)) {
    if (spec.start_from_still) {
      if (plan == BodyPlan::Fish) return phraser.pick<std::string>({"starting from a hover", "initially hovering in place"});
      if (plan == BodyPlan::Snake) return phraser.pick<std::string>({"starting motionless", "initially lying still"});
      return phraser.pick<std::string>({"starting still", "from a standstill", "starting from standing still", "initially standing still"});
    }
    if (plan == BodyPlan::Fish) return phraser.pick<std::string>({"already swimming", "already in motion"});
    if (spec.action == Action::Turn) return phraser.pick<std::string>({"already stepping", "already in motion"});
    return phraser.pick<std::string>({"already in motion", "already moving", is_gait(spec.action) ? "in mid-stride" : "on the move"});
  }
  if (spec.action == Action::GetUp) {
    if (lowering_action(creature.plan) == Action::Sit) {
      return phraser.pick<std::string>({"sitting at first", "from a sitting position", "starting seated"});
    }
    return phraser.pick<std::string>({"lying on the ground at first", "from lying down", "starting on the ground"});
  }
  if (plan == BodyPlan::Fish) return phraser.pick<std::string>({"initially hovering", "holding still in the water"});
  if (plan == BodyPlan::Snake) return phraser.pick<std::string>({"lying on the ground", "initially stretched out on the ground"});
  std::vector<std::string> options = {"initially standing", "starting from a standing pose"};
  if (legs > 0) options.push_back("standing on its " + (legs <= 10 ? number_word(legs) : "many") + " legs");
  return phraser.pick(options);
}

// Part-level detail: clauses that are true of this plan and action, as participles.
std::vector<std::string> part_details(const Creature& creature, const MotionSpec& spec, Phraser& phraser) {
  const BodyPlan own = creature.plan;
  const BodyPlan plan = moves_like(own);
  const bool arms = has_limb(creature, LimbKind::Arm);
  const bool wings = has_limb(creature, LimbKind::Wing);
  const bool tail = has_limb(creature, LimbKind::Tail);
  const bool jaw = has_limb(creature, LimbKind::Jaw);
  const bool head = has_limb(creature, LimbKind::Head) || has_limb(creature, LimbKind::Neck);
  const bool fins = has_limb(creature, LimbKind::Fin);
  const bool legs = has_limb(creature, LimbKind::Leg);
  const bool trunk = has_limb(creature, LimbKind::Trunk);
  std::vector<std::string> main;    // the most telling clause, one is chosen
  std::vector<std::string> extra;   // secondary motion, one may be added
  switch (spec.action) {
    case Action::Walk:
    case Action::Run:
    case Action::Trot:
    case Action::Gallop:
    case Action::Turn:
      switch (own == BodyPlan::Hopper ? own : plan) {
        case BodyPlan::Hopper:
          main = {"pushing off with both feet together", "its feet landing side by side",
                  "bouncing on its long hind feet"};
          extra.push_back("its tail held out behind for balance");
          break;
        case BodyPlan::Biped:
        case BodyPlan::Bird:
          main = {"alternating its legs", "stepping with one foot after the other"};
          if (spec.action == Action::Run) main.push_back("with a moment in the air between strides");
          if (arms) extra.push_back(spec.action == Action::Run ? "pumping its arms" : "its arms swinging opposite its legs");
          if (wings) extra.push_back("its wings folded against its body");
          break;
        case BodyPlan::Hexapod:
          main = {"lifting three legs at a time in a tripod gait", "moving its legs in alternating tripods",
                  "always keeping at least three legs on the ground"};
          break;
        case BodyPlan::Spider:
          main = {"moving its legs in waves from back to front", "its legs stepping in a wave from back to front",
                  "each leg stepping just after the one behind it"};
          if (own == BodyPlan::Crab) extra.push_back("its claws held up in front");
          break;
        case BodyPlan::Centipede:
          main = {"its many legs rippling in waves from back to front", "moving its legs in waves from back to front"};
          break;
        default:
          if (spec.action == Action::Trot) {
            main = {"moving diagonal legs together", "its diagonal legs striking the ground in pairs"};
          } else if (spec.action == Action::Gallop) {
            main = {"with a moment of flight in each stride", "reaching out with its front legs and gathering its hind legs"};
          } else if (spec.action == Action::Turn) {
            main = {"stepping around with small steps", "shuffling its feet as it turns"};
          } else {
            main = {"moving one leg at a time", "in a four-beat walk", "each hind foot stepping just before the front foot on its side"};
          }
          if (head && spec.action != Action::Turn) extra.push_back("its head nodding with each stride");
          if (wings) extra.push_back("its wings folded at its sides");
          break;
      }
      if (tail && plan != BodyPlan::Centipede && !is_arthropod(plan)) extra.push_back("its tail swaying behind it");
      if (trunk) extra.push_back("its trunk swinging");
      break;
    case Action::Slither:
      main = {"throwing its body into s-shaped curves", "undulating from side to side", "its body following the path of its head"};
      break;
    case Action::Swim:
      main = {"beating its tail from side to side", "sending a wave down its body to its tail"};
      if (fins) extra.push_back("its fins sculling");
      break;
    case Action::Fly:
      main = {"beating its wings", "with steady wing beats"};
      if (legs) extra.push_back("its legs tucked under its body");
      if (classify_turn(spec) != TurnClass::Straight) extra.push_back("banking into the turn");
      break;
    case Action::Glide:
      main = {"its wings spread wide and still", "holding its wings outstretched"};
      if (legs) extra.push_back("its legs tucked under its body");
      if (classify_turn(spec) != TurnClass::Straight) extra.push_back("banking into the turn");
      break;
    case Action::TakeOff:
      main = {"crouching, then pushing off with its legs", "beating its wings hard to climb", "climbing on strong wing beats"};
      extra.push_back("tucking its legs in as it rises");
      break;
    case Action::FlapWings:
      main = {"spreading its wings wide", "staying on the ground"};
      break;
    case Action::Idle:
      if (plan == BodyPlan::Fish) {
        main = {"its fins sculling softly", "its tail swaying a little"};
      } else if (plan == BodyPlan::Snake) {
        main = {"breathing slowly", "swaying its head a little"};
      } else {
        main = {"breathing slowly", "its chest rising and falling"};
        if (head && plan != BodyPlan::Snake) extra.push_back("looking around");
        if (legs) extra.push_back("shifting its weight");
        if (tail && !is_arthropod(plan) && plan != BodyPlan::Snake) extra.push_back("its tail swaying");
      }
      break;
    case Action::Sit:
      if (plan == BodyPlan::Biped) {
        main = {"bending its knees and lowering its hips to the ground", "leaning forward as it goes down"};
      } else if (plan == BodyPlan::Bird) {
        main = {"bending its legs", "lowering its body over its feet"};
      } else {
        main = {"lowering its hindquarters while its front legs stay straight", "folding its hind legs"};
      }
      break;
    case Action::LieDown:
      main = {"folding its legs", "lowering its belly to the ground"};
      break;
    case Action::Jump:
      main = {"crouching first, then pushing off with its legs", "tucking its legs in the air"};
      extra.push_back("landing and absorbing the impact");
      break;
    case Action::Wave:
      if (spec.side == Side::None) {
        main = {"its arms raised high", "swinging its hands from side to side", "its forearms swaying back and forth"};
        extra.push_back("then lowering its arms again");
      } else {
        main = {"its arm raised high", "swinging its hand from side to side", "its forearm swaying back and forth"};
        extra.push_back("then lowering its arm again");
      }
      break;
    case Action::RaiseHands:
      if (spec.side == Side::None) {
        main = {"stretching its arms straight up", "its hands high above its head", "reaching for the sky"};
        extra.push_back("holding them there");
      } else {
        main = {"stretching its arm straight up", "its hand high above its head", "reaching up"};
        extra.push_back("holding it there");
      }
      break;
    case Action::Point:
      main = {"its arm held straight out in front", "stretching its arm forward", "its arm level with its shoulder"};
      break;
    case Action::Clap:
      main = {"bringing its hands together in front of its chest", "its hands meeting in front of it again and again"};
      break;
    case Action::Bow:
      main = {"bending forward at the waist", "lowering its head and upper body", "tipping its torso forward"};
      extra.push_back("then straightening up again");
      break;
    case Action::Crouch:
      main = {"bending its knees deeply", "lowering its hips", "getting low to the ground"};
      extra.push_back("staying down");
      break;
    case Action::Kick:
      main = {"lifting its knee, then snapping its leg out", "swinging its leg up in front of it",
              "standing on one leg as it kicks"};
      extra.push_back("its arms out for balance");
      break;
    case Action::Shake:
      main = {"its body twisting rapidly from side to side", "rolling its body quickly one way and the other"};
      if (head) extra.push_back("its head whipping around");
      if (tail) extra.push_back("its tail whipping from side to side");
      break;
    case Action::JumpingJacks:
      main = {"jumping its feet apart and together", "hopping its legs out and in"};
      extra.push_back("swinging its arms up over its head and down");
      break;
    case Action::Stretch:
      main = {"reaching its arms high above its head", "its arms stretched straight up"};
      extra.push_back("leaning to one side and then the other");
      break;
    case Action::Dance:
      main = {"stepping from foot to foot", "swaying its hips from side to side", "bouncing to the beat"};
      extra.push_back("swinging its arms");
      break;
    case Action::GetUp:
      main = {"pushing itself up with its legs", "straightening its legs"};
      extra.push_back("then standing still");
      break;
    case Action::Eat:
      main = {"its head down to the ground", "its muzzle close to the ground", "bending its neck down to the ground"};
      if (jaw) extra.push_back("chewing");
      extra.push_back("then raising its head again");
      break;
    case Action::Attack:
      if (own == BodyPlan::Crab) {
        main = {"lifting its claws high", "its claws raised and spread wide"};
        break;
      }
      if (trunk) {
        main = {"curling its trunk up high", "lifting its trunk over its head"};
        break;
      }
      switch (own == BodyPlan::Dinosaur ? own : plan) {
        case BodyPlan::Biped:
          main = {"twisting its torso into the punch", "winding up first", "raising its guard first"};
          break;
        case BodyPlan::Hexapod:
        case BodyPlan::Spider:
          main = {"raising its front legs high, then slamming them down", "rearing up, then striking down with its front legs"};
          break;
        case BodyPlan::Snake:
          main = {"coiling its neck into an s-curve, then striking forward", "drawing its head back, then striking"};
          break;
        case BodyPlan::Fish:
          main = {"with a sudden burst of speed", "beating its tail hard"};
          break;
        case BodyPlan::Bird:
          main = {"jabbing its beak down repeatedly", "leaning forward and pecking three times"};
          break;
        case BodyPlan::Centipede:
          main = {"rearing its head up, then striking down", "raising its head, then lunging"};
          break;
        default:
          main = {"winding up, then lunging", "crouching back, then lunging"};
          break;
      }
      if (jaw) extra.push_back("snapping its jaws");
      break;
  }
  std::vector<std::string> chosen;
  if (!main.empty()) chosen.push_back(phraser.pick(main));
  if (!extra.empty() && phraser.chance(0.6)) chosen.push_back(phraser.pick(extra));
  return chosen;
}

std::string stop_clause(const MotionSpec& spec, Phraser& phraser) {
  if (!spec.stop_at_end || !is_locomotion(spec.action) || spec.action == Action::Fly || spec.action == Action::Glide) {
    return "";
  }
  return phraser.pick<std::string>({"then comes to a stop", "and then stops", "before coming to a halt", "and finally holds still"});
}

std::string join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string out;
  for (const std::string& part : parts) {
    if (part.empty()) continue;
    if (!out.empty()) out += separator;
    out += part;
  }
  return out;
}

// "walks forward quickly" and the like: the verb with its direction and speed.
std::string travel_predicate(const Verb& verb, const MotionSpec& spec, SpeedClass speed, Phraser& phraser) {
  // Phrasal verbs ("sails through the air", "runs at a gallop") carry their own direction.
  const std::string direction = verb.finite.find(' ') == std::string::npos ? direction_words(spec, phraser) : "";
  const std::string pace = speed_words(speed, phraser);
  const bool one_word = pace.find(' ') == std::string::npos && !pace.empty() && pace != "fast" && pace != "leisurely";
  if (one_word && phraser.chance(0.3)) return join({pace + " " + verb.finite, direction}, " ");
  return join({verb.finite, direction, pace}, " ");
}

// A jump with less horizontal speed than this share of the typical one is "in place".
constexpr double kJumpInPlaceRatio = 0.2;

bool jumps_forward(const Creature& creature, const MotionSpec& spec) {
  return spec.speed >= kJumpInPlaceRatio * typical_speed(creature, Action::Jump);
}

// The predicate of the mid and long captions, without turn and stop clauses.
std::string predicate(const Creature& creature, const MotionSpec& spec, const Verb& verb, SpeedClass speed,
                      Phraser& phraser) {
  switch (spec.action) {
    case Action::Turn:
      return turn_in_place_words(spec, phraser);
    case Action::Jump:
      return verb.finite + " " +
             (jumps_forward(creature, spec) ? phraser.pick<std::string>({"forward", "ahead"})
                                            : phraser.pick<std::string>({"in place", "straight up", "on the spot"}));
    case Action::Attack:
      if (creature.plan == BodyPlan::Biped) {
        const std::string s = side_word(spec.side);
        return phraser.pick<std::string>({"punches with its " + s + " fist", "throws a " + s + " punch",
                                          "strikes with its " + s + " arm"});
      }
      if (creature.plan == BodyPlan::Bird || creature.plan == BodyPlan::GroundBird || verb.finite.find(' ') != std::string::npos) {
        return verb.finite;
      }
      return verb.finite + " " + phraser.pick<std::string>({"forward", "at something in front of it"});
    case Action::TakeOff:
      return verb.finite + " " + phraser.pick<std::string>({"and climbs into the air", "and rises into the air, flying forward",
                                                            "from the ground and climbs"});
    case Action::FlapWings:
      return phraser.pick<std::string>({"stands and " + verb.finite, verb.finite + " while standing on the ground"});
    case Action::Wave: {
      if (spec.side == Side::None) {
        return phraser.pick<std::string>({verb.finite + " with both hands", verb.finite + " with both arms",
                                          "waves both arms over its head"});
      }
      const std::string s = side_word(spec.side);
      return phraser.pick<std::string>({verb.finite + " with its " + s + " hand", "raises its " + s + " hand and waves",
                                        verb.finite + " its " + s + " arm"});
    }
    case Action::RaiseHands: {
      if (spec.side == Side::None) {
        return phraser.pick<std::string>({"raises both hands", "raises both arms above its head", "puts both hands up"});
      }
      const std::string s = side_word(spec.side);
      return phraser.pick<std::string>({"raises its " + s + " hand", "lifts its " + s + " arm above its head",
                                        "puts its " + s + " hand up"});
    }
    case Action::Point: {
      const std::string s = side_word(spec.side);
      return phraser.pick<std::string>({"points forward with its " + s + " hand", "points ahead with its " + s + " arm",
                                        "points at something in front of it with its " + s + " hand"});
    }
    case Action::Kick: {
      const std::string s = side_word(spec.side);
      return phraser.pick<std::string>({"kicks with its " + s + " leg", "kicks forward with its " + s + " foot",
                                        "throws a " + s + " kick"});
    }
    case Action::Crouch:
      return verb.finite + phraser.pick<std::string>({"", " and stays low", " and holds the pose"});
    case Action::Sit:
    case Action::LieDown:
      return verb.finite + phraser.pick<std::string>({"", " and stays there", " and rests"});
    case Action::Idle:
    case Action::Clap:
    case Action::Bow:
    case Action::Eat:
    case Action::Shake:
    case Action::JumpingJacks:
    case Action::Stretch:
    case Action::Dance:
    case Action::GetUp:
      return verb.finite;
    default:
      return travel_predicate(verb, spec, speed, phraser);
  }
}

}  // namespace

TurnClass classify_turn(const MotionSpec& spec) {
  if (!is_locomotion(spec.action)) return TurnClass::Straight;
  const double rate = std::abs(spec.turn_rate);
  if (rate < kVeerDegreesPerSecond) return TurnClass::Straight;
  if (spec.action != Action::Turn && std::abs(heading_change_degrees(spec)) >= kCircleDegrees) return TurnClass::Circle;
  return rate >= kTurnDegreesPerSecond ? TurnClass::Turn : TurnClass::Veer;
}

Captions caption_motion(const Creature& creature, const MotionSpec& spec, uint64_t phrasing_seed) {
  if (!supports_action(creature.plan, spec.action)) {
    throw std::invalid_argument("caption_motion: a " + std::string(body_plan_name(creature.plan)) + " cannot " +
                                std::string(action_name(spec.action)));
  }
  Phraser phraser(phrasing_seed);
  const bool travels = is_locomotion(spec.action) && spec.action != Action::Turn;
  const SpeedClass speed = travels ? classify_speed(spec.speed, typical_speed(creature, spec.action)) : SpeedClass::Normal;
  const std::vector<Verb> verbs = action_verbs(creature, spec, speed);
  const std::string plain_subject = noun_phrase(creature);
  // The manner: an adjective on the subject or an adverbial after the predicate, in every level.
  const std::string adjective = manner_adjective(spec.manner, phraser);
  const bool manner_on_subject = !adjective.empty() && phraser.chance(0.5);
  const auto with_manner = [&](const std::string& noun) {  // "a dog" -> "a weary dog"
    if (!manner_on_subject) return noun;
    return (starts_with_vowel_sound(adjective) ? "an " : "a ") + adjective + " " + noun.substr(noun.find(' ') + 1);
  };
  const std::string subject = with_manner(plain_subject);
  // A quarter of the short captions leave the species out, as people often do ("an animal trots", "someone
  // waves"); drawn apart from the other choices so that those stay as they are.
  Phraser naming(mix_seed(phrasing_seed, 0x6E0A));
  const std::string generic = naming.chance(0.25) ? naming.pick(generic_nouns(creature)) : "";
  const bool unnamed = !generic.empty() && (!manner_on_subject || generic.find(' ') != std::string::npos);
  const std::string short_subject = unnamed ? with_manner(generic) : subject;  // not "a weary someone"
  const std::string adverbial =
      manner_on_subject ? "" : manner_adverbial(spec.manner, is_locomotion(spec.action), phraser);

  // One verb for all three levels: each level adds to the one before.
  const Verb& verb = phraser.pick(verbs);
  Captions captions;
  // Short: the action only (and the manner).
  captions.short_text = join({phraser.chance(0.7) ? short_subject + " " + verb.finite
                                                 : short_subject + " is " + verb.participle,
                              adverbial},
                             " ");

  // Mid: + speed, direction and turning (or, for actions that do not travel, one part-level clause).
  const std::string predicate_text = join({predicate(creature, spec, verb, speed, phraser), adverbial}, ", ");
  const std::string core = subject + " " + predicate_text;
  const std::vector<std::string> details = part_details(creature, spec, phraser);
  const std::string turn = travels ? turn_participle(spec, phraser, true) : "";
  if (travels) {
    captions.mid_text = join({core, turn}, ", ");
  } else {
    captions.mid_text = join({core, details.empty() ? "" : details.front()}, ", ");
  }

  // Long: + initial posture, all part-level detail, and the stop.
  const std::string posture = initial_posture(creature, spec, phraser);
  std::vector<std::string> parts;
  if (phraser.chance(0.75)) {
    parts = {posture, core};
  } else {
    parts = {subject + ", " + posture + ", " + predicate_text};
  }
  for (const std::string& clause : details) parts.push_back(clause);
  parts.push_back(manner_detail(spec.manner, phraser));
  parts.push_back(turn);
  parts.push_back(stop_clause(spec, phraser));
  captions.long_text = join(parts, ", ");
  return captions;
}

}  // namespace nec::zoo
