// Kinematic segmentation and captions of long takes: scripted quadruped takes
// with known activities and boundaries, left/right signs, frame-rate and
// heading invariance, and invariants on real MANN dog takes.
#include "nec/motion/bvh.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/segment.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>

namespace nec {
namespace {

constexpr double kStandingHeight = 48.0;  // root above the floor when standing: hip 3 + legs 40 + paw 5

// A small dog in a natural rest pose: +Y up, facing +Z, its left side at +X.
Skeleton quadruped() {
  Skeleton s;
  const auto rot = ChannelLayout::rotations(EulerOrder::ZXY);
  s.add_joint("Hips", -1, Vec3::Zero(), ChannelLayout::position_rotations(EulerOrder::ZXY));
  const int spine = s.add_joint("Spine", 0, Vec3(0, 0, 20), rot);
  const int chest = s.add_joint("Chest", spine, Vec3(0, 0, 20), rot);
  const int neck = s.add_joint("Neck", chest, Vec3(0, 8, 10), rot);
  const int head = s.add_joint("Head", neck, Vec3(0, 5, 10), rot);
  s.end_sites.push_back({head, Vec3(0, 0, 12)});
  for (const char* side : {"Left", "Right"}) {
    const double x = std::string(side) == "Left" ? 6.0 : -6.0;
    const int shoulder = s.add_joint(std::string(side) + "Shoulder", chest, Vec3(x, -3, 0), rot);
    const int elbow = s.add_joint(std::string(side) + "ForeArm", shoulder, Vec3(0, -20, 0), rot);
    const int paw = s.add_joint(std::string(side) + "Hand", elbow, Vec3(0, -20, 0), rot);
    s.end_sites.push_back({paw, Vec3(0, -5, 0)});
    const int hip = s.add_joint(std::string(side) + "UpLeg", 0, Vec3(x, -3, 0), rot);
    const int knee = s.add_joint(std::string(side) + "Leg", hip, Vec3(0, -20, 0), rot);
    const int foot = s.add_joint(std::string(side) + "Foot", knee, Vec3(0, -20, 0), rot);
    s.end_sites.push_back({foot, Vec3(0, -5, 0)});
  }
  const int tail = s.add_joint("Tail", 0, Vec3(0, 2, -10), rot);
  s.end_sites.push_back({tail, Vec3(0, 0, -15)});
  s.validate();
  return s;
}

// The state of the scripted dog at one instant.
struct Pose1 {
  Vec3 ground = Vec3::Zero();  // root position on the floor (y ignored)
  double yaw = 0.0;            // degrees about +Y, + = left
  double lie = 0.0;            // 0 standing .. 1 lying
  double sit = 0.0;            // 0 standing .. 1 sitting
  double lift = 0.0;           // extra root height (jumps), file units
};

// Samples `script` (seconds -> state) into a take at `fps`.
Clip scripted_take(double seconds, double fps, const std::function<Pose1(double)>& script) {
  Clip clip{quadruped(), {}, {}};
  const Skeleton& s = clip.skeleton;
  const int frames = static_cast<int>(std::lround(seconds * fps));
  clip.motion = Motion::rest(s, frames, fps);
  const auto joint = [&](const char* name) { return s.find(name); };
  for (int t = 0; t < frames; ++t) {
    const Pose1 p = script(t / fps);
    const double height = kStandingHeight * (1.0 - 0.75 * p.lie - 0.75 * p.sit) + p.lift;
    clip.motion.translation(t, 0) = Vec3(p.ground.x(), height, p.ground.z());
    // Sitting pitches the trunk up by 45 degrees (rotation about -X lifts +Z).
    const Quat pitch = axis_rotation(0, -45.0 * p.sit);
    clip.motion.rotation(t, 0) = axis_rotation(1, p.yaw) * pitch;
    // Lying folds the hind legs backward and the forelegs forward; sitting
    // folds the hind legs and keeps the forelegs vertical.
    const Quat hind = axis_rotation(0, 90.0 * p.lie + 135.0 * p.sit);
    const Quat fore = axis_rotation(0, -90.0 * p.lie + 45.0 * p.sit);
    for (const char* name : {"LeftUpLeg", "RightUpLeg"}) clip.motion.rotation(t, joint(name)) = hind;
    for (const char* name : {"LeftShoulder", "RightShoulder"}) clip.motion.rotation(t, joint(name)) = fore;
  }
  return clip;
}

double smooth_step(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

// Stand 3 s, walk forward 3 s at `walk` body sizes/s, turn in place 3 s at
// `turn` degrees/s, lie down (0.5 s) and stay down 3 s.
Clip stand_walk_turn_lie(double fps, double turn, double walk = 0.8) {
  const double body = quadruped().diameter();
  return scripted_take(12.5, fps, [=](double t) {
    Pose1 p;
    const double walked = std::clamp(t - 3.0, 0.0, 3.0) * walk * body;
    p.ground = Vec3(0, 0, walked);
    p.yaw = std::clamp(t - 6.0, 0.0, 3.0) * turn;
    p.lie = smooth_step((t - 9.0) / 0.5);
    return p;
  });
}

std::string describe(const TakeSegmentation& cut) {
  std::string out;
  for (const Segment& s : cut.segments) {
    out += std::to_string(s.begin / cut.signals.fps).substr(0, 5) + "-" +
           std::to_string(s.end / cut.signals.fps).substr(0, 5) + " " + s.captions[0] + "\n";
  }
  return out;
}

bool has_label(const Segment& s, const std::string& label) {
  return std::find(s.labels.begin(), s.labels.end(), label) != s.labels.end();
}

void expect_covering(const TakeSegmentation& cut, int frame_count, const SegmentOptions& options) {
  ASSERT_FALSE(cut.segments.empty());
  EXPECT_EQ(cut.segments.front().begin, 0);
  EXPECT_EQ(cut.segments.back().end, frame_count);
  const double fps = cut.signals.fps;
  for (size_t i = 0; i < cut.segments.size(); ++i) {
    const Segment& s = cut.segments[i];
    if (i > 0) {
      EXPECT_EQ(s.begin, cut.segments[i - 1].end);
    }
    const double seconds = (s.end - s.begin) / fps;
    if (frame_count / fps >= options.min_seconds) {
      EXPECT_GE(seconds, options.min_seconds - 1.0 / fps) << i;
    }
    EXPECT_LE(seconds, options.max_seconds + 1.0 / fps) << i;
    ASSERT_FALSE(s.captions.empty()) << i;
    ASSERT_FALSE(s.labels.empty()) << i;
    const bool starts_with_subject = s.captions[0].rfind("a " + options.creature + " ", 0) == 0 ||
                                     s.captions[0].rfind("an " + options.creature + " ", 0) == 0;
    EXPECT_TRUE(starts_with_subject) << s.captions[0];
    ASSERT_FALSE(s.phases.empty());
    EXPECT_EQ(s.phases.front().begin, s.begin);
    EXPECT_EQ(s.phases.back().end, s.end);
  }
}

TEST(Segment, TestRigHasItsLeftSideAtPlusX) {
  // The premise of the left/right checks below: facing +Z with +Y up, left is +X.
  const Skeleton s = quadruped();
  const Pose pose = forward_kinematics(s, Motion::rest(s, 1, 30));
  EXPECT_GT(pose.position(0, s.find("LeftShoulder")).x(), 0.0);
  EXPECT_GT(pose.position(0, s.find("Head")).z(), 0.0);
  // A positive yaw about +Y turns +Z towards +X: counter-clockwise from above, a left turn.
  EXPECT_GT((axis_rotation(1, 30.0) * Vec3::UnitZ()).x(), 0.0);
}

TEST(Segment, ScriptedTakeGivesKnownBoundariesAndLabels) {
  const Clip take = stand_walk_turn_lie(60.0, 60.0);
  const SegmentOptions options;
  const TakeSegmentation cut = segment_take(take, options);
  SCOPED_TRACE(describe(cut));
  EXPECT_EQ(cut.signals.facing_source, "left/right joints");
  EXPECT_GE(cut.signals.chest, 0);
  EXPECT_NEAR(cut.signals.standing_height, kStandingHeight, 0.5);
  expect_covering(cut, take.motion.frame_count, options);
  ASSERT_EQ(cut.segments.size(), 4u);

  // Seconds: gait and turn changes are found within half the speed and turn
  // windows; a posture change where the root starts to sink.
  const double expected_boundaries[] = {3.0, 6.0, 9.0};
  const double tolerances[] = {0.25, 0.5, 0.2};
  for (int i = 0; i < 3; ++i) {
    const double boundary = cut.segments[i].end / 60.0;
    EXPECT_NEAR(boundary, expected_boundaries[i], tolerances[i]) << "boundary " << i;
  }
  const Segment& stand = cut.segments[0];
  const Segment& walk = cut.segments[1];
  const Segment& turn = cut.segments[2];
  const Segment& lie = cut.segments[3];

  EXPECT_EQ(stand.activity, Activity::Stand);
  EXPECT_TRUE(has_label(stand, "stands still"));
  EXPECT_EQ(stand.captions[0], "a dog stands still");

  EXPECT_EQ(walk.activity, Activity::Walk);
  EXPECT_EQ(walk.turn, Turn::None);
  EXPECT_EQ(walk.captions[0], "a dog walks forward");
  EXPECT_NEAR(walk.measurements.forward_speed, 0.8, 0.1);
  EXPECT_NEAR(walk.measurements.lateral_speed, 0.0, 0.02);

  EXPECT_EQ(turn.activity, Activity::Stand);
  EXPECT_EQ(turn.turn, Turn::Left);
  EXPECT_TRUE(has_label(turn, "turns left"));
  EXPECT_EQ(turn.captions[0], "a dog turns left in place");
  EXPECT_NEAR(turn.measurements.turn_rate, 60.0, 10.0);
  EXPECT_LT(turn.measurements.mean_speed, 0.05);

  EXPECT_EQ(lie.activity, Activity::Lie);
  EXPECT_TRUE(has_label(lie, "lies down"));
  EXPECT_EQ(lie.captions[0], "a dog lies down");
  EXPECT_LT(lie.measurements.height_ratio, 0.3);
  EXPECT_LT(std::abs(lie.measurements.trunk_pitch), 5.0);
}

TEST(Segment, RightTurnHasTheOppositeSign) {
  const TakeSegmentation cut = segment_take(stand_walk_turn_lie(60.0, -60.0));
  SCOPED_TRACE(describe(cut));
  ASSERT_EQ(cut.segments.size(), 4u);
  const Segment& turn = cut.segments[2];
  EXPECT_EQ(turn.turn, Turn::Right);
  EXPECT_TRUE(has_label(turn, "turns right"));
  EXPECT_FALSE(has_label(turn, "turns left"));
  EXPECT_EQ(turn.captions[0], "a dog turns right in place");
  EXPECT_NEAR(turn.measurements.turn_rate, -60.0, 10.0);
}

TEST(Segment, HeadingAloneIsTheHeadingOfTheFullMeasurement) {
  const Clip take = stand_walk_turn_lie(60.0, -60.0);
  const std::vector<double> heading = measure_heading(take);
  EXPECT_EQ(heading, measure_kinematics(take).heading);
  ASSERT_EQ(heading.size(), static_cast<size_t>(take.motion.frame_count));
  EXPECT_NEAR(heading[9 * 60] - heading[6 * 60], -180.0, 20.0);  // 3 s turning right at 60 degrees/s
  EXPECT_TRUE(measure_heading(Clip{take.skeleton, Motion::rest(take.skeleton, 0, 60.0), {}}).empty());
}

TEST(Segment, WalkingAlongACurveTurnsTheRightWay) {
  // Walk 5 s at 0.8 body sizes/s while the heading changes by `rate` degrees/s;
  // the path is integrated from the heading so the creature walks where it faces.
  const double body = quadruped().diameter();
  for (const double rate : {40.0, -40.0}) {
    const double fps = 60.0;
    Vec3 position = Vec3::Zero();
    double last = 0.0;
    const Clip take = scripted_take(5.0, fps, [&](double t) {
      const double yaw = rate * t;
      const double step = t - last;
      last = t;
      position += step * 0.8 * body * Vec3(std::sin(yaw * M_PI / 180), 0, std::cos(yaw * M_PI / 180));
      Pose1 p;
      p.ground = position;
      p.yaw = yaw;
      return p;
    });
    // Sanity of the script: a left turn curves the path towards +X.
    const Vec3 end = take.motion.translation(take.motion.frame_count - 1, 0);
    EXPECT_EQ(end.x() > 0, rate > 0);
    const TakeSegmentation cut = segment_take(take);
    SCOPED_TRACE(describe(cut));
    ASSERT_EQ(cut.segments.size(), 1u);
    const Segment& s = cut.segments[0];
    EXPECT_EQ(s.activity, Activity::Walk);
    EXPECT_EQ(s.turn, rate > 0 ? Turn::Left : Turn::Right);
    EXPECT_EQ(s.captions[0], rate > 0 ? "a dog walks and turns left" : "a dog walks and turns right");
    EXPECT_NEAR(s.measurements.turn_rate, rate, 4.0);
    EXPECT_NEAR(s.measurements.forward_speed, 0.8, 0.05);
  }
}

TEST(Segment, LabelsDoNotDependOnFrameRateOrWhereTheTakeFaces) {
  const TakeSegmentation reference = segment_take(stand_walk_turn_lie(60.0, 60.0));
  for (const double fps : {24.0, 30.0, 120.0}) {
    const TakeSegmentation cut = segment_take(stand_walk_turn_lie(fps, 60.0));
    SCOPED_TRACE("fps " + std::to_string(fps) + "\n" + describe(cut));
    ASSERT_EQ(cut.segments.size(), reference.segments.size());
    for (size_t i = 0; i < cut.segments.size(); ++i) {
      EXPECT_EQ(cut.segments[i].captions[0], reference.segments[i].captions[0]);
      EXPECT_NEAR(cut.segments[i].end / fps, reference.segments[i].end / 60.0, 0.1) << i;
    }
  }
  // Rotate and move the whole take: 137 degrees about +Y and elsewhere on the floor.
  Clip turned = stand_walk_turn_lie(60.0, 60.0);
  const Quat yaw = axis_rotation(1, 137.0);
  for (int t = 0; t < turned.motion.frame_count; ++t) {
    turned.motion.translation(t, 0) = yaw * turned.motion.translation(t, 0) + Vec3(250, 0, -75);
    turned.motion.rotation(t, 0) = yaw * turned.motion.rotation(t, 0);
  }
  const TakeSegmentation cut = segment_take(turned);
  SCOPED_TRACE(describe(cut));
  ASSERT_EQ(cut.segments.size(), reference.segments.size());
  for (size_t i = 0; i < cut.segments.size(); ++i) {
    EXPECT_EQ(cut.segments[i].captions[0], reference.segments[i].captions[0]);
    EXPECT_EQ(cut.segments[i].end, reference.segments[i].end);
  }
}

// Renames joints of a take: every `from` substring becomes `to` (applied in order).
Clip renamed(Clip clip, const std::vector<std::pair<std::string, std::string>>& rules) {
  for (auto& name : clip.skeleton.names) {
    for (const auto& [from, to] : rules) {
      const size_t at = name.find(from);
      if (at != std::string::npos) name.replace(at, from.size(), to);
    }
  }
  return clip;
}

TEST(Segment, FacingComesFromSidesThenHeadThenRoot) {
  const Clip take = stand_walk_turn_lie(60.0, 60.0);
  const TakeSegmentation reference = segment_take(take);
  const struct {
    std::vector<std::pair<std::string, std::string>> rules;
    const char* source;
  } cases[] = {
      {{{"Left", "Tmp"}, {"Right", "Left"}, {"Tmp", "Right"}},
       "left/right joints"},  // sides swapped: the head corrects them
      {{{"Left", "First"}, {"Right", "Second"}}, "head"},
      {{{"Left", "First"}, {"Right", "Second"}, {"Head", "Snout"}}, "root +Z axis"},
  };
  for (const auto& c : cases) {
    const TakeSegmentation cut = segment_take(renamed(take, c.rules));
    SCOPED_TRACE(std::string(c.source) + "\n" + describe(cut));
    EXPECT_EQ(cut.signals.facing_source, c.source);
    ASSERT_EQ(cut.segments.size(), reference.segments.size());
    for (size_t i = 0; i < cut.segments.size(); ++i) {
      EXPECT_EQ(cut.segments[i].captions[0], reference.segments[i].captions[0]);
    }
    EXPECT_NEAR(cut.segments[1].measurements.forward_speed, 0.8, 0.1);
  }
}

TEST(Segment, GaitFollowsSpeedRelativeToBodySize) {
  const double body = quadruped().diameter();
  const struct {
    double speed;
    Activity gait;
    const char* caption;
  } cases[] = {{0.6, Activity::Walk, "a dog walks forward"},
               {2.0, Activity::Trot, "a dog trots forward"},
               {3.5, Activity::Run, "a dog runs forward"}};
  for (const auto& c : cases) {
    const Clip take = scripted_take(4.0, 60.0, [&](double t) {
      Pose1 p;
      p.ground = Vec3(0, 0, c.speed * body * t);
      return p;
    });
    const TakeSegmentation cut = segment_take(take);
    SCOPED_TRACE(describe(cut));
    ASSERT_EQ(cut.segments.size(), 1u);
    EXPECT_EQ(cut.segments[0].activity, c.gait);
    EXPECT_EQ(cut.segments[0].captions[0], c.caption);
    EXPECT_NEAR(cut.segments[0].measurements.mean_speed, c.speed, 0.1 * c.speed);
  }
  // Backward: the same speed against the facing direction.
  const Clip back = scripted_take(4.0, 60.0, [&](double t) {
    Pose1 p;
    p.ground = Vec3(0, 0, -0.5 * body * t);
    return p;
  });
  const TakeSegmentation cut = segment_take(back);
  ASSERT_EQ(cut.segments.size(), 1u);
  EXPECT_EQ(cut.segments[0].captions[0], "a dog walks backward");
  EXPECT_LT(cut.segments[0].measurements.forward_speed, -0.4);
}

TEST(Segment, SittingNeedsTheChestAboveTheRoot) {
  // Stand 3 s, sit down over 0.5 s, sit 3.5 s.
  const Clip take = scripted_take(7.0, 60.0, [](double t) {
    Pose1 p;
    p.sit = smooth_step((t - 3.0) / 0.5);
    return p;
  });
  const TakeSegmentation cut = segment_take(take);
  SCOPED_TRACE(describe(cut));
  ASSERT_EQ(cut.segments.size(), 2u);
  EXPECT_EQ(cut.segments[0].activity, Activity::Stand);
  EXPECT_EQ(cut.segments[1].activity, Activity::Sit);
  EXPECT_TRUE(has_label(cut.segments[1], "sits"));
  EXPECT_EQ(cut.segments[1].captions[0], "a dog sits down");  // the segment starts where the root starts to sink
  EXPECT_NEAR(cut.segments[1].measurements.trunk_pitch, 45.0, 2.0);
  EXPECT_NEAR(cut.segments[0].end / 60.0, 3.1, 0.1);
}

TEST(Segment, AJumpIsAFlightAboveTheFloor) {
  // Stand 2 s, jump straight up (0.6 s flight, 25 units high at the top), stand 2.4 s.
  // The scripted legs do not step, so the feet rest on the floor only while standing.
  const Clip take = scripted_take(5.0, 60.0, [&](double t) {
    Pose1 p;
    const double x = (t - 2.0) / 0.6;
    if (x > 0 && x < 1) p.lift = 4 * 25.0 * x * (1 - x);
    return p;
  });
  const TakeSegmentation cut = segment_take(take);
  SCOPED_TRACE(describe(cut));
  int jump_frames = 0;
  for (Activity a : cut.signals.activity) jump_frames += a == Activity::Jump;
  EXPECT_NEAR(jump_frames / 60.0, 0.5, 0.1);  // the top of the flight is slow enough to look like a rest
  int smoothed_jump_frames = 0;
  for (const Phase& p : cut.phases) smoothed_jump_frames += p.activity == Activity::Jump ? p.end - p.begin : 0;
  EXPECT_NEAR(smoothed_jump_frames / 60.0, 0.6, 0.05);
  bool any_jump = false;
  for (const Segment& s : cut.segments) {
    if (s.jumps) {
      any_jump = true;
      EXPECT_TRUE(has_label(s, "jumps"));
      EXPECT_NE(s.captions[0].find("jumps"), std::string::npos) << s.captions[0];
      EXPECT_NEAR(s.measurements.max_rise, 25.0 / cut.signals.standing_height, 0.05);
    }
  }
  EXPECT_TRUE(any_jump);
  // A hop of a quarter of the threshold is no jump.
  const Clip hop = scripted_take(5.0, 60.0, [&](double t) {
    Pose1 p;
    const double x = (t - 2.0) / 0.3;
    if (x > 0 && x < 1) p.lift = 4 * 3.0 * x * (1 - x);
    return p;
  });
  for (const Segment& s : segment_take(hop).segments) EXPECT_FALSE(s.jumps);
}

TEST(Segment, LongActivitiesAreSplitAndShortTakesKeptWhole) {
  SegmentOptions options;
  options.creature = "elephant";
  const Clip still = scripted_take(14.0, 30.0, [](double) { return Pose1{}; });
  const TakeSegmentation cut = segment_take(still, options);
  expect_covering(cut, still.motion.frame_count, options);
  ASSERT_EQ(cut.segments.size(), 3u);  // 14 s in equal parts of at most 6 s
  for (const Segment& s : cut.segments) {
    EXPECT_EQ(s.captions[0], "an elephant stands still");
    EXPECT_NEAR((s.end - s.begin) / 30.0, 14.0 / 3.0, 0.05);
  }
  const Clip short_take = scripted_take(1.0, 30.0, [](double) { return Pose1{}; });
  const TakeSegmentation short_cut = segment_take(short_take, options);
  ASSERT_EQ(short_cut.segments.size(), 1u);
  EXPECT_EQ(short_cut.segments[0].end, short_take.motion.frame_count);
  const Clip empty = scripted_take(0.0, 30.0, [](double) { return Pose1{}; });
  EXPECT_TRUE(segment_take(empty, options).segments.empty());
}

TEST(Segment, InvalidOptionsAreRejected) {
  const Clip take = scripted_take(1.0, 30.0, [](double) { return Pose1{}; });
  SegmentOptions bad;
  bad.max_seconds = 3.0;  // less than 2 × min_seconds
  EXPECT_THROW(segment_take(take, bad), std::invalid_argument);
  bad = SegmentOptions{};
  bad.trot_speed = 0.1;  // below walk_speed
  EXPECT_THROW(segment_take(take, bad), std::invalid_argument);
  bad = SegmentOptions{};
  bad.creature.clear();
  EXPECT_THROW(segment_take(take, bad), std::invalid_argument);
}

// Real MANN dog takes (skipped without ../shared/data): coverage, clip
// lengths and captions everywhere, plus activities checked by eye on the
// root height, trunk pitch and speed traces of two takes.
TEST(Segment, RealDogTakes) {
  const std::string data = testing::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "no shared data";
  const std::string dir = data + "/mann_dog";
  const SegmentOptions options;
  int checked = 0;  // the shared data is there: every take must be
  for (const char* name :
       {"D1_004_KAN01_001.bvh", "D1_010_KAN01_002.bvh", "D1_ex04_KAN02_002.bvh", "D1_049_KAN01_001.bvh"}) {
    const std::string path = dir + "/" + name;
    if (!std::filesystem::exists(path)) {
      ADD_FAILURE() << path << " missing from the shared data";
      continue;
    }
    ++checked;
    const Clip take = read_bvh(path);
    const TakeSegmentation cut = segment_take(take, options);
    SCOPED_TRACE(std::string(name) + "\n" + describe(cut));
    expect_covering(cut, take.motion.frame_count, options);
    EXPECT_EQ(cut.signals.facing_source, "left/right joints");
    EXPECT_GT(cut.signals.standing_height, 0.4 * cut.signals.body_size);
    EXPECT_LT(cut.signals.standing_height, 0.65 * cut.signals.body_size);
    const std::string file(name);
    if (file == "D1_004_KAN01_001.bvh") {  // sits ~10 s (hips 10 units up, chest pitched 40°), then stands
      EXPECT_EQ(cut.segments.front().activity, Activity::Sit);
      EXPECT_TRUE(has_label(cut.segments.back(), "stands still"));
    } else if (file == "D1_010_KAN01_002.bvh") {  // 2.6 s at 4–5 body sizes/s
      ASSERT_EQ(cut.segments.size(), 1u);
      EXPECT_EQ(cut.segments[0].activity, Activity::Run);
    } else if (file == "D1_049_KAN01_001.bvh") {  // sits, walks in tight left circles (~240°/s), sits
      EXPECT_EQ(cut.segments.front().activity, Activity::Sit);
      EXPECT_EQ(cut.segments.back().activity, Activity::Sit);
      bool circles_left = false;
      for (const Segment& s : cut.segments)
        circles_left = circles_left || (s.turn == Turn::Left && s.measurements.turn_rate > 180);
      EXPECT_TRUE(circles_left);
    }
  }
  EXPECT_EQ(checked, 4);
}

}  // namespace
}  // namespace nec
