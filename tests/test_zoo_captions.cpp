// Multi-level zoo captions: true to the spec (species, turn direction, speed
// words, start/stop, gait detail), three levels of detail, many phrasings,
// deterministic.
#include "nec/zoo/zoo_captions.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <sstream>

namespace nec::zoo {
namespace {

// Lower-case words of a caption, punctuation removed.
std::vector<std::string> words_of(const std::string& text) {
  std::string cleaned;
  for (char c : text) cleaned += std::isalnum(static_cast<unsigned char>(c)) || c == '-' ? c : ' ';
  std::vector<std::string> words;
  std::stringstream stream(cleaned);
  for (std::string w; stream >> w;) words.push_back(w);
  return words;
}

bool has_word(const std::string& text, const std::string& word) {
  const auto words = words_of(text);
  return std::find(words.begin(), words.end(), word) != words.end();
}

bool has_any(const std::string& text, const std::vector<std::string>& stems) {
  for (const std::string& w : words_of(text)) {
    for (const std::string& stem : stems) {
      if (w.rfind(stem, 0) == 0) return true;
    }
  }
  return text.find("high speed") != std::string::npos && std::find(stems.begin(), stems.end(), "high") != stems.end();
}

const std::vector<std::string> kSlowWords = {"slow", "leisurely", "unhurried", "stroll", "amble", "plod"};
const std::vector<std::string> kFastWords = {"quick", "fast", "rapid", "high", "sprint", "dash", "rac", "scurr", "skitter"};

// Many specs over every plan and action, with the spec the synthesizer makes.
struct Case {
  Creature creature;
  MotionSpec spec;
};

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (BodyPlan plan : kAllBodyPlans) {
    for (uint64_t seed = 0; seed < 3; ++seed) {
      const Creature creature = make_creature(plan, seed);
      int k = 0;
      for (Action action : supported_actions(plan)) {
        for (double ratio : {0.5, 1.0, 2.0}) {
          MotionSpec spec;
          spec.action = action;
          spec.seed = seed * 100 + k;
          spec.speed = typical_speed(creature, action) * ratio;
          spec.turn_rate = (k % 5 - 2) * 25.0;
          spec.start_from_still = k % 2 == 0;
          spec.stop_at_end = k % 3 == 0;
          spec.side = k % 2 ? Side::Left : Side::Right;
          cases.push_back({creature, synthesize_motion(creature, spec).spec});
          ++k;
        }
      }
    }
  }
  return cases;
}

class ZooCaptions : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { cases_ = new std::vector<Case>(all_cases()); }
  static void TearDownTestSuite() {
    delete cases_;
    cases_ = nullptr;
  }
  static std::vector<Case>* cases_;
};
std::vector<Case>* ZooCaptions::cases_ = nullptr;

// The words a short caption may name a creature with when it leaves the species out.
const std::vector<std::string> kGenericNouns = {"someone", "figure", "character", "animal", "creature", "reptile",
                                                "bird", "monster", "critter"};

bool names_the_creature(const std::string& line, const Creature& creature) {
  return has_word(line, creature.species) ||
         std::any_of(kGenericNouns.begin(), kGenericNouns.end(), [&](const std::string& w) { return has_word(line, w); });
}

// The mid and long captions name the species; the short one does, or (about a quarter of them) says what people
// say when they do not name it.
TEST_F(ZooCaptions, EveryLevelNamesTheSpeciesAndAddsDetail) {
  int unnamed = 0, shorts = 0;
  for (const Case& c : *cases_) {
    for (uint64_t phrasing = 0; phrasing < 4; ++phrasing) {
      const Captions captions = caption_motion(c.creature, c.spec, phrasing);
      EXPECT_TRUE(has_word(captions.mid_text, c.creature.species)) << captions.mid_text;
      EXPECT_TRUE(has_word(captions.long_text, c.creature.species)) << captions.long_text;
      EXPECT_TRUE(names_the_creature(captions.short_text, c.creature)) << captions.short_text;
      ++shorts;
      unnamed += !has_word(captions.short_text, c.creature.species);
      for (const std::string& line : captions.lines()) {
        EXPECT_EQ(line.find('\n'), std::string::npos);
        EXPECT_FALSE(line.empty());
      }
      EXPECT_LT(words_of(captions.short_text).size(), words_of(captions.long_text).size()) << captions.long_text;
      EXPECT_LE(words_of(captions.short_text).size(), words_of(captions.mid_text).size() + 1) << captions.mid_text;
      EXPECT_LT(words_of(captions.mid_text).size(), words_of(captions.long_text).size()) << captions.long_text;
    }
  }
  EXPECT_GT(unnamed, shorts / 6);
  EXPECT_LT(unnamed, shorts / 3);
}

TEST_F(ZooCaptions, TurnsAreNamedWithTheRightSide) {
  int left = 0, right = 0, straight = 0;
  for (const Case& c : *cases_) {
    for (uint64_t phrasing = 0; phrasing < 4; ++phrasing) {
      const Captions captions = caption_motion(c.creature, c.spec, phrasing);
      const TurnClass turn = classify_turn(c.spec);
      const Action a = c.spec.action;
      const bool gesture = a == Action::Wave || a == Action::RaiseHands || a == Action::Point || a == Action::Kick;
      const bool sided =
          (a == Action::Attack && c.creature.plan == BodyPlan::Biped) || (gesture && c.spec.side != Side::None);
      for (const std::string& line : {captions.mid_text, captions.long_text}) {
        if (sided) {
          // The punching, waving or pointing arm, the kicking leg: not a turn.
          EXPECT_TRUE(has_word(line, c.spec.side == Side::Left ? "left" : "right")) << line;
          EXPECT_FALSE(has_word(line, c.spec.side == Side::Left ? "right" : "left")) << line;
        } else if (turn == TurnClass::Straight) {
          EXPECT_FALSE(has_word(line, "left") || has_word(line, "right")) << line << " (turn rate " << c.spec.turn_rate << ")";
          ++straight;
        } else if (c.spec.turn_rate > 0) {
          EXPECT_TRUE(has_word(line, "left")) << line;
          EXPECT_FALSE(has_word(line, "right")) << line << " (turn rate " << c.spec.turn_rate << ")";
          ++left;
        } else {
          EXPECT_TRUE(has_word(line, "right")) << line;
          EXPECT_FALSE(has_word(line, "left")) << line << " (turn rate " << c.spec.turn_rate << ")";
          ++right;
        }
      }
      EXPECT_FALSE(has_word(captions.short_text, "left") && has_word(captions.short_text, "right"));
    }
  }
  EXPECT_GT(left, 0);
  EXPECT_GT(right, 0);
  EXPECT_GT(straight, 0);
}

TEST_F(ZooCaptions, SpeedWordsMatchTheSpeed) {
  int slow = 0, fast = 0, normal = 0;
  for (const Case& c : *cases_) {
    const Action action = c.spec.action;
    if (!is_locomotion(action) || action == Action::Turn) continue;
    const SpeedClass speed = classify_speed(c.spec.speed, typical_speed(c.creature, action));
    for (uint64_t phrasing = 0; phrasing < 6; ++phrasing) {
      const Captions captions = caption_motion(c.creature, c.spec, phrasing);
      for (const std::string& line : {captions.mid_text, captions.long_text}) {
        if (speed == SpeedClass::Slow) {
          EXPECT_TRUE(has_any(line, kSlowWords)) << line;
          EXPECT_FALSE(has_any(line, kFastWords)) << line;
          ++slow;
        } else if (speed == SpeedClass::Fast) {
          EXPECT_TRUE(has_any(line, kFastWords)) << line;
          EXPECT_FALSE(has_any(line, kSlowWords)) << line;
          ++fast;
        } else {
          EXPECT_FALSE(has_any(line, kSlowWords) || has_any(line, kFastWords)) << line;
          ++normal;
        }
      }
      // The short caption may only use a speed verb that agrees.
      if (speed != SpeedClass::Fast) {
        EXPECT_FALSE(has_any(captions.short_text, kFastWords)) << captions.short_text;
      }
      if (speed != SpeedClass::Slow) {
        EXPECT_FALSE(has_any(captions.short_text, kSlowWords)) << captions.short_text;
      }
    }
  }
  EXPECT_GT(slow, 0);
  EXPECT_GT(fast, 0);
  EXPECT_GT(normal, 0);
}

TEST_F(ZooCaptions, LongCaptionTellsStartStopAndGait) {
  for (const Case& c : *cases_) {
    const Captions captions = caption_motion(c.creature, c.spec, 5);
    const std::string& text = captions.long_text;
    const bool travels = is_locomotion(c.spec.action);
    if (travels && c.spec.start_from_still) {
      EXPECT_TRUE(has_any(text, {"still", "standstill", "hover", "motionless"})) << text;
    }
    if (travels && !c.spec.start_from_still) {
      EXPECT_FALSE(has_any(text, {"standstill"})) << text;
    }
    if (travels && c.spec.stop_at_end) {
      EXPECT_TRUE(has_any(text, {"stop", "halt", "holds"})) << text;
    }
    if (!c.spec.stop_at_end) {
      EXPECT_FALSE(has_any(text, {"stop", "halt"})) << text;
    }
    if (c.creature.plan == BodyPlan::Hexapod && is_gait(c.spec.action)) {
      EXPECT_TRUE(text.find("tripod") != std::string::npos || text.find("three legs") != std::string::npos) << text;
    }
    if ((c.creature.plan == BodyPlan::Spider || c.creature.plan == BodyPlan::Centipede) && is_gait(c.spec.action)) {
      EXPECT_TRUE(text.find("wave") != std::string::npos || text.find("behind it") != std::string::npos) << text;
    }
    if (c.spec.action == Action::Trot) {
      EXPECT_NE(text.find("diagonal"), std::string::npos) << text;
    }
  }
}

TEST_F(ZooCaptions, JumpsSayForwardOrInPlace) {
  const Creature dog = make_creature(BodyPlan::Quadruped, 1);
  MotionSpec spec;
  spec.action = Action::Jump;
  spec.speed = 0.0;
  for (uint64_t phrasing = 0; phrasing < 8; ++phrasing) {
    const std::string mid = caption_motion(dog, synthesize_motion(dog, spec).spec, phrasing).mid_text;
    EXPECT_TRUE(has_any(mid, {"place", "straight", "spot"})) << mid;
    EXPECT_FALSE(has_any(mid, {"forward", "ahead"})) << mid;
  }
  spec.speed = typical_speed(dog, Action::Jump);
  for (uint64_t phrasing = 0; phrasing < 8; ++phrasing) {
    const std::string mid = caption_motion(dog, synthesize_motion(dog, spec).spec, phrasing).mid_text;
    EXPECT_TRUE(has_any(mid, {"forward", "ahead"})) << mid;
  }
}

TEST_F(ZooCaptions, GesturesNameTheirHandOrLegAndStayInPlace) {
  const Creature person = make_creature(BodyPlan::Biped, 2);
  for (Action action : {Action::Wave, Action::RaiseHands, Action::Point, Action::Kick}) {
    for (Side side : {Side::Left, Side::Right, Side::None}) {
      MotionSpec spec;
      spec.action = action;
      spec.side = side;
      spec.seed = 5;
      const MotionSpec made = synthesize_motion(person, spec).spec;
      const bool both = made.side == Side::None;
      EXPECT_EQ(both, side == Side::None && (action == Action::Wave || action == Action::RaiseHands));
      for (uint64_t phrasing = 0; phrasing < 6; ++phrasing) {
        const std::string mid = caption_motion(person, made, phrasing).mid_text;
        if (both) {
          EXPECT_TRUE(has_word(mid, "both")) << mid;
        } else {
          EXPECT_TRUE(has_word(mid, made.side == Side::Left ? "left" : "right")) << mid;
          EXPECT_FALSE(has_word(mid, made.side == Side::Left ? "right" : "left")) << mid;
        }
        EXPECT_FALSE(has_any(mid, {"quick", "slow", "leisurely"})) << mid;  // no travel speed
      }
    }
  }
  for (Action action : {Action::Clap, Action::Bow, Action::Crouch}) {
    MotionSpec spec;
    spec.action = action;
    const std::string mid = caption_motion(person, synthesize_motion(person, spec).spec, 1).mid_text;
    EXPECT_FALSE(has_any(mid, {"left", "right", "ahead", "quick", "slow"})) << mid;
  }
}

TEST_F(ZooCaptions, BackingUpAndSidesteppingSayWhichWay) {
  for (BodyPlan plan : {BodyPlan::Biped, BodyPlan::Spider}) {
    const Creature creature = make_creature(plan, 3);
    for (double direction : {180.0, 90.0, -90.0}) {
      MotionSpec spec;
      spec.action = Action::Walk;
      spec.direction = direction;
      spec.speed = 0.6 * typical_speed(creature, Action::Walk);
      const MotionSpec made = synthesize_motion(creature, spec).spec;
      for (uint64_t phrasing = 0; phrasing < 8; ++phrasing) {
        const std::string mid = caption_motion(creature, made, phrasing).mid_text;
        if (direction == 180.0) {
          EXPECT_TRUE(has_any(mid, {"back", "reverse"})) << mid;
        } else {
          EXPECT_TRUE(has_any(mid, {direction > 0 ? "left" : "right"})) << mid;
          EXPECT_FALSE(has_any(mid, {direction > 0 ? "right" : "left"})) << mid;
        }
        EXPECT_FALSE(has_any(mid, {"forward", "ahead"})) << mid;
      }
    }
  }
}

TEST_F(ZooCaptions, MannersAreNamedAtEveryLevel) {
  const std::map<Manner, std::vector<std::string>> words = {
      {Manner::Tired, {"tired", "tiredly", "weary", "wearily", "exhausted", "sluggishly"}},
      {Manner::Energetic, {"energetic", "energetically", "lively", "spirited", "spring", "energy", "briskly"}},
      {Manner::Cautious, {"cautious", "cautiously", "wary", "warily", "nervous", "carefully"}},
      {Manner::Proud, {"proud", "proudly", "confident", "confidently", "haughty", "chest"}}};
  for (BodyPlan plan : {BodyPlan::Biped, BodyPlan::Quadruped, BodyPlan::Spider}) {
    const Creature creature = make_creature(plan, 4);
    for (const auto& [manner, said] : words) {
      for (Action action : {Action::Walk, Action::Idle}) {
        MotionSpec spec;
        spec.action = action;
        spec.manner = manner;
        const MotionSpec made = synthesize_motion(creature, spec).spec;
        for (uint64_t phrasing = 0; phrasing < 6; ++phrasing) {
          const Captions captions = caption_motion(creature, made, phrasing);
          for (const std::string& line : captions.lines()) {
            const bool named = std::any_of(said.begin(), said.end(), [&](const std::string& w) { return has_word(line, w); });
            EXPECT_TRUE(named) << manner_name(manner) << ": " << line;
            EXPECT_TRUE(names_the_creature(line, creature)) << line;
          }
        }
      }
    }
  }
}

// The plans modelled on users' rigs are worded as what they are: a kangaroo hops (never walks), a crab's attack
// is its claws', an elephant trumpets with its trunk, a dinosaur bites (it does not peck); species by name.
TEST_F(ZooCaptions, NewPlansAreWordedAsWhatTheyAre) {
  for (const Case& c : *cases_) {
    const BodyPlan plan = c.creature.plan;
    if (moves_like(plan) == plan) continue;
    for (uint64_t phrasing = 0; phrasing < 4; ++phrasing) {
      const Captions captions = caption_motion(c.creature, c.spec, phrasing);
      const std::string& mid = captions.mid_text;
      if (plan == BodyPlan::Hopper && (c.spec.action == Action::Walk || c.spec.action == Action::Run)) {
        EXPECT_TRUE(has_any(mid, {"hop", "bound"})) << mid;
        EXPECT_FALSE(has_any(mid, {"walk", "runs", "running"})) << mid;
      }
      if (c.spec.action == Action::Attack) {
        if (plan == BodyPlan::Crab) {
          EXPECT_TRUE(has_word(mid, "claws")) << mid;
        } else if (plan == BodyPlan::Elephant) {
          EXPECT_TRUE(has_any(mid, {"trunk", "trumpet"})) << mid;
        } else if (plan == BodyPlan::Dinosaur) {
          EXPECT_FALSE(has_any(mid, {"peck"})) << mid;
        } else if (plan == BodyPlan::GroundBird) {
          EXPECT_TRUE(has_any(mid, {"peck"})) << mid;
        }
      }
    }
  }
  std::set<std::string> species;
  for (BodyPlan plan : {BodyPlan::Crab, BodyPlan::Ungulate, BodyPlan::Elephant, BodyPlan::GroundBird,
                        BodyPlan::Hopper, BodyPlan::Dinosaur}) {
    for (uint64_t seed = 0; seed < 30; ++seed) species.insert(make_creature(plan, seed).species);
  }
  EXPECT_EQ(species, (std::set<std::string>{"crab", "deer", "goat", "camel", "giraffe", "elephant", "flamingo", "heron",
                                            "chicken", "ostrich", "kangaroo", "wallaby", "dinosaur", "tyrannosaurus"}));
}

// Getting up says so, and the long caption says where it starts from.
TEST_F(ZooCaptions, GettingUpSaysUpAndWhereItStarts) {
  for (const Case& c : *cases_) {
    if (c.spec.action != Action::GetUp) continue;
    for (uint64_t phrasing = 0; phrasing < 4; ++phrasing) {
      const Captions captions = caption_motion(c.creature, c.spec, phrasing);
      for (const std::string& line : captions.lines()) EXPECT_TRUE(has_any(line, {"up", "rises", "rising", "lift"})) << line;
      EXPECT_TRUE(has_any(captions.long_text, {"lying", "sitting", "seated", "ground"})) << captions.long_text;
    }
  }
}

TEST(ZooCaptionsBasics, ManyPhrasingsAndDeterministic) {
  const Creature spider = make_creature(BodyPlan::Spider, 7);
  MotionSpec spec;
  spec.action = Action::Walk;
  spec.speed = 1.6 * typical_speed(spider, Action::Walk);
  spec.turn_rate = 40.0;
  spec.start_from_still = true;
  spec = synthesize_motion(spider, spec).spec;
  std::set<std::string> shorts, mids, longs;
  for (uint64_t phrasing = 0; phrasing < 60; ++phrasing) {
    const Captions c = caption_motion(spider, spec, phrasing);
    shorts.insert(c.short_text);
    mids.insert(c.mid_text);
    longs.insert(c.long_text);
    const Captions again = caption_motion(spider, spec, phrasing);
    EXPECT_EQ(c.lines(), again.lines());
  }
  std::printf("60 phrasings: %zu short, %zu mid, %zu long distinct; e.g. \"%s\"\n", shorts.size(), mids.size(), longs.size(),
              longs.begin()->c_str());
  EXPECT_GE(shorts.size(), 4u);
  EXPECT_GE(mids.size(), 15u);
  EXPECT_GE(longs.size(), 30u);
}

TEST(ZooCaptionsBasics, TurnClasses) {
  MotionSpec spec;
  spec.action = Action::Walk;
  spec.turn_rate = 3.0;
  EXPECT_EQ(classify_turn(spec), TurnClass::Straight);
  spec.turn_rate = -20.0;
  EXPECT_EQ(classify_turn(spec), TurnClass::Veer);
  spec.turn_rate = 50.0;
  EXPECT_EQ(classify_turn(spec), TurnClass::Turn);
  spec.turn_rate = 100.0;  // 400 degrees over 4 s
  EXPECT_EQ(classify_turn(spec), TurnClass::Circle);
  spec.action = Action::Idle;
  EXPECT_EQ(classify_turn(spec), TurnClass::Straight);
  const Creature fish = make_creature(BodyPlan::Fish, 0);
  spec.action = Action::Walk;
  EXPECT_THROW(caption_motion(fish, spec, 0), std::invalid_argument);
}

}  // namespace
}  // namespace nec::zoo
