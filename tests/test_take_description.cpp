// Take descriptions: CMU-style free text read into verb phrases and activity kinds, matched to the clips the
// segmenter cuts a take into; and a described real take through the corpus reader.
#include "nec/corpus/corpus.h"
#include "nec/corpus/take_description.h"

#include "test_support.h"

#include <filesystem>

namespace nec {
namespace {

using testing::TempDir;

std::vector<std::string> first_phrases(const TakeDescription& d) {
  std::vector<std::string> out;
  for (const DescribedPart& p : d.parts) out.push_back(p.phrases.front());
  return out;
}

std::vector<DescribedKind> kinds(const TakeDescription& d) {
  std::vector<DescribedKind> out;
  for (const DescribedPart& p : d.parts) out.push_back(p.kind);
  return out;
}

// A clip of 100 frames made of phases (activity, frames), in order.
Segment clip_of(std::vector<std::pair<Activity, int>> phases, bool jumps = false) {
  Segment s;
  for (const auto& [activity, frames] : phases) {
    s.phases.push_back({s.end, s.end + frames, activity, Turn::None});
    s.end += frames;
  }
  s.jumps = jumps;
  return s;
}

TEST(TakeDescription, PartsBecomeThirdPersonVerbPhrases) {
  const TakeDescription d = parse_take_description("Jumping jacks, side twists, bend over, jog");
  EXPECT_EQ(d.theme, "");
  EXPECT_EQ(first_phrases(d),
            (std::vector<std::string>{"does jumping jacks", "does side twists", "bends over", "jogs"}));
  EXPECT_EQ(kinds(d), (std::vector<DescribedKind>{DescribedKind::InPlace, DescribedKind::InPlace,
                                                  DescribedKind::InPlace, DescribedKind::Travel}));

  const TakeDescription soccer = parse_take_description("soccer - kick ball");
  EXPECT_EQ(soccer.theme, "soccer");
  EXPECT_EQ(first_phrases(soccer), std::vector<std::string>{"kicks ball"});

  // Alternatives, adjectives before a verb noun, gerunds, "self".
  const TakeDescription run = parse_take_description("run/jog");
  ASSERT_EQ(run.parts.size(), 1u);
  EXPECT_EQ(run.parts[0].phrases, (std::vector<std::string>{"runs", "jogs"}));
  EXPECT_EQ(first_phrases(parse_take_description("slow walk")), std::vector<std::string>{"walks slowly"});
  EXPECT_EQ(first_phrases(parse_take_description("forward jump")), std::vector<std::string>{"jumps forward"});
  EXPECT_EQ(kinds(parse_take_description("forward jump")), std::vector<DescribedKind>{DescribedKind::Jump});
  EXPECT_EQ(first_phrases(parse_take_description("dance - folding arms, pirouettes")),
            (std::vector<std::string>{"folds arms", "does pirouettes"}));
  EXPECT_EQ(first_phrases(parse_take_description("lower self to ground")),
            std::vector<std::string>{"lowers oneself to ground"});
  // A dribble travels only with a direction; standing up is low.
  EXPECT_EQ(kinds(parse_take_description("basketball - forward dribble, dribble, shoot")),
            (std::vector<DescribedKind>{DescribedKind::Travel, DescribedKind::InPlace, DescribedKind::InPlace}));
  EXPECT_EQ(kinds(parse_take_description("sit on stepstool, stand up")),
            (std::vector<DescribedKind>{DescribedKind::Low, DescribedKind::Low}));
}

TEST(TakeDescription, DetailsJoinThePartBeforeThem) {
  const TakeDescription d = parse_take_description("sit on stepstool, ankle on other knee, hand on chin");
  ASSERT_EQ(d.parts.size(), 1u);
  EXPECT_EQ(d.parts[0].phrases.front(), "sits on stepstool, with ankle on other knee, with hand on chin");
  const TakeDescription walk = parse_take_description("navigate - walk forward, backward, sideways");
  ASSERT_EQ(walk.parts.size(), 1u);
  EXPECT_EQ(walk.parts[0].phrases.front(), "walks forward, backward, sideways");
  EXPECT_EQ(walk.parts[0].kind, DescribedKind::Travel);
  // A detail with nothing before it stands alone.
  EXPECT_EQ(first_phrases(parse_take_description("arms held high")),
            std::vector<std::string>{"moves with arms held high"});
  // A detail cut short is dropped.
  EXPECT_EQ(first_phrases(parse_take_description("climb, jump down, legs push off against")),
            (std::vector<std::string>{"climbs", "jumps down"}));
  EXPECT_THROW(parse_take_description(" , "), std::invalid_argument);
}

TEST(TakeDescription, ClipsGetThePartsTheirKinematicsAgreeWith) {
  const TakeDescription d = parse_take_description("jumping jacks, side twists, squats, jog");
  const Segment jogging = clip_of({{Activity::Stand, 20}, {Activity::Run, 80}});
  const Segment standing = clip_of({{Activity::Stand, 100}});
  EXPECT_EQ(described_clip_captions(d, jogging, "person", false),
            (std::vector<std::string>{"a person jogs", "the person jogs"}));
  EXPECT_EQ(described_clip_captions(d, standing, "person", false).front(),
            "a person does jumping jacks, does side twists and does squats");
  // A take that is one clip gets every part.
  EXPECT_EQ(described_clip_captions(d, standing, "person", true).front(),
            "a person does jumping jacks, does side twists, does squats and jogs");

  // Jumps need the segmenter's jump, sitting a low phase.
  const TakeDescription jump = parse_take_description("playground - forward jumps, turn around");
  const Segment jumping = clip_of({{Activity::Stand, 40}, {Activity::Jump, 20}, {Activity::Stand, 40}}, true);
  const auto jump_captions = described_clip_captions(jump, jumping, "person", false);
  EXPECT_EQ(jump_captions, (std::vector<std::string>{"a person jumps forward and turns around",
                                                     "the person jumps forward and turns around",
                                                     "a person plays on a playground and jumps forward and turns "
                                                     "around"}));
  const TakeDescription sit = parse_take_description("sit on high stool, stand up");
  EXPECT_EQ(described_clip_captions(sit, standing, "person", false), std::vector<std::string>{});
  EXPECT_EQ(described_clip_captions(sit, clip_of({{Activity::Stand, 50}, {Activity::Sit, 50}}), "person", false)
                .front(),
            "a person sits on high stool and stands up");
  // Without an agreeing part the theme alone is still true; an elephant gets "an".
  const TakeDescription ball = parse_take_description("basketball - forward dribble");
  EXPECT_EQ(described_clip_captions(ball, standing, "elephant", false),
            std::vector<std::string>{"an elephant plays basketball"});
  // In-place parts of a take that also travels stay off its travelling clips.
  EXPECT_EQ(described_clip_captions(parse_take_description("walk, wave"), jogging, "person", false).front(),
            "a person walks");
}

TEST(TakeDescription, DescribedRealTakeIsCutAndCaptionedByAgreement) {
  const std::string bvh = testing::cmu_bvh_dir() + "/01_01.bvh";
  if (!std::filesystem::exists(bvh)) GTEST_SKIP() << "assimp-testmodels is not installed";
  TempDir dir;
  // CMU's own description of this take: forward jumps on a playground, then a turn.
  const std::string csv = dir.write("descriptions.csv", "file,description\n" + bvh + ",\"playground - forward jumps, "
                                                                                   "turn around\"\n");
  CorpusOptions options;
  options.captions.descriptions.push_back(CaptionTable::read(csv));
  options.segment.creature = "person";
  const CorpusResult corpus = load_corpus({{bvh, "cmu"}}, options);
  ASSERT_EQ(corpus.files.size(), 1u);
  EXPECT_EQ(corpus.files[0].described, 1);
  ASSERT_GT(corpus.files[0].segments, 1);
  int jumping = 0;
  for (const CacheEntry& e : corpus.entries) {
    ASSERT_GE(e.captions.size(), 2u) << e.id;
    // Every clip keeps the segmenter's own caption beside the description's.
    EXPECT_TRUE(std::any_of(e.captions.begin(), e.captions.end(),
                            [](const std::string& c) { return c.rfind("a person ", 0) == 0; }));
    jumping += e.captions.front().find("jumps forward") != std::string::npos;
  }
  EXPECT_GT(jumping, 0);
}

}  // namespace
}  // namespace nec
