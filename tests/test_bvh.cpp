// BVH reader and writer: messy-but-valid input, bad input, round trips on real files.
#include "nec/motion/bvh.h"
#include "nec/motion/error.h"
#include "nec/motion/kinematics.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <charconv>
#include <cstring>
#include <random>

namespace nec {
namespace {

constexpr const char* kTwoJoints =
    "HIERARCHY\n"
    "ROOT Hips\n"
    "{\n"
    "  OFFSET 0 0 0\n"
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "  JOINT Spine\n"
    "  {\n"
    "    OFFSET 0 10 0\n"
    "    CHANNELS 3 Zrotation Xrotation Yrotation\n"
    "    End Site\n"
    "    {\n"
    "      OFFSET 0 5 0\n"
    "    }\n"
    "  }\n"
    "}\n"
    "MOTION\n"
    "Frames: 2\n"
    "Frame Time: 0.0333333\n"
    "1 2 3 0 0 0 90 0 0\n"
    "4 5 6 0 90 0 0 0 0\n";

// Largest difference between two clips: positions relative to the diameter,
// rotations as geodesic angle.
struct ClipDifference {
  double position = 0.0;  // max |FK position difference| / diameter
  double rotation = 0.0;  // max geodesic angle (radians)
};

ClipDifference compare_clips(const Clip& a, const Clip& b) {
  ClipDifference d;
  const Pose pa = forward_kinematics(a.skeleton, a.motion);
  const Pose pb = forward_kinematics(b.skeleton, b.motion);
  const double scale = std::max(a.skeleton.diameter(), 1e-9);
  d.position = testing::max_position_difference(pa.positions, pb.positions) / scale;
  for (size_t i = 0; i < a.motion.rotations.size(); ++i) {
    d.rotation = std::max(d.rotation, geodesic_distance(a.motion.rotations[i], b.motion.rotations[i]));
  }
  return d;
}

TEST(BvhReader, ReadsAMinimalFile) {
  const Clip clip = parse_bvh(kTwoJoints, "two.bvh");
  ASSERT_EQ(clip.skeleton.joint_count(), 2);
  EXPECT_EQ(clip.skeleton.names[1], "Spine");
  EXPECT_EQ(clip.skeleton.parents[1], 0);
  ASSERT_EQ(clip.skeleton.end_sites.size(), 1u);
  EXPECT_EQ(clip.motion.frame_count, 2);
  EXPECT_NEAR(clip.motion.fps, 30.0, 1e-4);
  EXPECT_NEAR((clip.motion.translation(1, 0) - Vec3(4, 5, 6)).norm(), 0.0, 1e-12);
  // Frame 0: Spine rotated 90 degrees about Z, so its end site lies along -X.
  const Pose pose = forward_kinematics(clip.skeleton, clip.motion);
  const Vec3 tip = end_site_positions(clip.skeleton, pose)[0];
  EXPECT_NEAR((tip - Vec3(1 - 5, 2 + 10, 3)).norm(), 0.0, 1e-9);
}

TEST(BvhReader, ToleratesMessyFormatting) {
  const std::string messy =
      "\xEF\xBB\xBFHIERARCHY\r\n"
      "ROOT Bip01 Pelvis {\r\n"
      "\tOFFSET\t0.0  0.0\t0.0\r\n"
      "\tCHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\r\n"
      "\tJOINT Bip01 L Thigh\r\n"
      "\t{\r\n"
      "\t\tOFFSET 1e1 -2.5E-1 +3\r\n"
      "\t\tCHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation\r\n"
      "\t\tEnd Site\r\n"
      "\t\t{\r\n"
      "\t\t\tOFFSET 0 -1 0\r\n"
      "\t\t}\r\n"
      "\t}\r\n"
      "}\r\n"
      "\r\n"
      "MOTION\r\n"
      "Frames:\t1\r\n"
      "Frame Time:\t.01\r\n"
      "\r\n"
      "0 1 2 3.5e1 0 0 10 -0.25 3 0 0 45\r\n"
      "\r\n";
  const Clip clip = parse_bvh(messy, "messy.bvh");
  ASSERT_EQ(clip.skeleton.joint_count(), 2);
  EXPECT_EQ(clip.skeleton.names[0], "Bip01 Pelvis");
  EXPECT_EQ(clip.skeleton.names[1], "Bip01 L Thigh");
  EXPECT_NEAR((clip.skeleton.offsets[1] - Vec3(10, -0.25, 3)).norm(), 0.0, 1e-12);
  EXPECT_EQ(clip.skeleton.channels[1].euler_order(), EulerOrder::YXZ);
  EXPECT_NEAR(clip.motion.fps, 100.0, 1e-9);
  // Position channels on a non-root joint replace its offset.
  EXPECT_NEAR((clip.motion.translation(0, 1) - Vec3(10, -0.25, 3)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(geodesic_distance(clip.motion.rotation(0, 1), axis_rotation(2, 45.0)), 0.0, 1e-9);
}

struct BadCase {
  const char* label;
  std::string text;
  const char* expected;  // substring of the error message
};

std::string with_motion(const std::string& motion_part) {
  std::string head = kTwoJoints;
  return head.substr(0, head.find("MOTION")) + motion_part;
}

// A root with one channel, `joints` joints without channels, `frames` frames of "0".
std::string joints_without_channels(int joints, int frames) {
  std::string text = "HIERARCHY\nROOT root\n{\nOFFSET 0 0 0\nCHANNELS 1 Xposition\n";
  for (int j = 0; j < joints; ++j) text += "JOINT j" + std::to_string(j) + "\n{\nOFFSET 0 0 0\n}\n";
  text += "}\nMOTION\nFrames: " + std::to_string(frames) + "\nFrame Time: 0.01\n";
  for (int t = 0; t < frames; ++t) text += "0\n";
  return text;
}

// A chain of `depth` + 1 joints, each the child of the one before.
std::string nested_joints(int depth) {
  std::string text = "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\n";
  for (int j = 1; j <= depth; ++j) text += "JOINT j" + std::to_string(j) + "\n{\nOFFSET 0 1 0\n";
  for (int j = 0; j <= depth; ++j) text += "}\n";
  return text + "MOTION\nFrames: 0\nFrame Time: 0.01\n";
}

TEST(BvhReader, RejectsBadInputWithFileLineAndReason) {
  const std::string good = kTwoJoints;
  const std::vector<BadCase> cases = {
      {"empty", "", "empty"},
      {"garbage", std::string("\x7f\x45\x4c\x46\x02\x01\x00\x00", 8), "HIERARCHY"},
      {"truncated hierarchy", good.substr(0, 60), "end of file"},
      {"missing brace", "HIERARCHY\nROOT Hips\n  OFFSET 0 0 0\n", "expected '{'"},
      {"unknown channel", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 1 Wrotation\n}\n", "unknown channel"},
      {"bad offset", "HIERARCHY\nROOT A\n{\nOFFSET 0 x 0\n}\n", "bad OFFSET"},
      {"nan offset", "HIERARCHY\nROOT A\n{\nOFFSET 0 nan 0\n}\n", "bad OFFSET"},
      {"too few values", with_motion("MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 3" + std::string(20, ' ') + "\n"), "has 3 values, expected 9"},
      {"too many values", with_motion("MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 3 4 5 6 7 8 9 10\n"), "more than 9"},
      {"inf value", with_motion("MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 3 inf 5 6 7 8 9\n"), "bad number 'inf'"},
      {"negative frames", with_motion("MOTION\nFrames: -3\nFrame Time: 0.1\n"), "bad frame count"},
      {"absurd frames", with_motion("MOTION\nFrames: 1000000000\nFrame Time: 0.1\n0 0 0 0 0 0 0 0 0\n"),
       "declares 1000000000 frames"},
      {"truncated motion", with_motion("MOTION\nFrames: 3\nFrame Time: 0.1\n" + std::string(18 * 3, ' ') +
                                       "0 0 0 0 0 0 0 0 0\n"), "file ends after 1 of 3"},
      {"zero frame time", with_motion("MOTION\nFrames: 1\nFrame Time: 0\n0 0 0 0 0 0 0 0 0\n"), "bad frame time"},
      {"duplicate names", "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nJOINT A\n{\nOFFSET 0 0 0\n}\n}\n", "duplicate joint"},
      // Found by tests/fuzz: the name "A{" was accepted but written back as "A{\n{", which reads as "A".
      {"brace in name", "HIERARCHY\nROOT A{ {\nOFFSET 0 0 0\n}\n", "ends with '{'"},
      // 1400 joints without channels and 12000 one-value frames (64 KB) took 1 GB and timed out the fuzzer.
      {"joints without channels", joints_without_channels(40, 1000), "more joint-frames than"},
      // 4096 nested joints (220 KB) overflowed the stack under ASan and in a 1 MB thread stack.
      {"deep nesting", nested_joints(1100), "nested more than 1024 deep"},
  };
  for (const BadCase& c : cases) {
    try {
      parse_bvh(c.text, "bad.bvh");
      ADD_FAILURE() << c.label << ": no error";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("bad.bvh"), std::string::npos) << c.label << ": " << message;
      EXPECT_NE(message.find(c.expected), std::string::npos) << c.label << ": " << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << c.label << ": one line expected";
    }
  }
}

TEST(BvhReader, ErrorNamesTheLine) {
  const std::string text = with_motion("MOTION\nFrames: 2\nFrame Time: 0.1\n0 0 0 0 0 0 0 0 0\n0 0 0 0 oops 0 0 0 0\n");
  try {
    parse_bvh(text, "lines.bvh");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lines.bvh:20:"), std::string::npos) << e.what();
  }
}

// Numbers are read as the correctly rounded double of their text, whatever its form: the root's position
// channels come back bit for bit as std::from_chars reads them (plain decimals take a faster path).
TEST(BvhReader, NumbersAreTheCorrectlyRoundedDoubleOfTheirText) {
  std::mt19937 rng(7);
  std::vector<std::string> texts = {"0", "-0", "-0.0", "+1.5", ".5", "5.", "-.25", "1e3", "-2.5E-3", "123456789012345678",
                                    "9007199254740993", "0.1000000000000000055511151231257827", "1.7976931348623157e308",
                                    "4.9e-324", "0.0000000000000000000001", "-12.345678901234567890"};
  std::uniform_int_distribution<int> digit(0, 9), length(1, 20), point(0, 20), sign(0, 1);
  while (texts.size() % 3 != 0 || texts.size() < 3000) {
    std::string text = sign(rng) ? "-" : "";
    const int digits = length(rng), dot = point(rng);
    for (int i = 0; i < digits; ++i) {
      if (i == dot) text += '.';
      text += static_cast<char>('0' + digit(rng));
    }
    texts.push_back(text);
  }
  std::string bvh = "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition Yposition Zposition\n"
                    "  End Site\n  {\n    OFFSET 0 1 0\n  }\n}\nMOTION\nFrames: " +
                    std::to_string(texts.size() / 3) + "\nFrame Time: 0.0333333\n";
  for (size_t i = 0; i < texts.size(); i += 3) bvh += texts[i] + " " + texts[i + 1] + " " + texts[i + 2] + "\n";
  const testing::TempDir dir;
  const Clip clip = read_bvh(dir.write("numbers.bvh", bvh));
  for (size_t i = 0; i < texts.size(); ++i) {
    const std::string& text = texts[i];
    const char* first = text.data() + (text[0] == '+' ? 1 : 0);
    double expected = 0.0;
    std::from_chars(first, text.data() + text.size(), expected);
    const double got = clip.motion.translation(static_cast<int>(i / 3), 0)[static_cast<int>(i % 3)];
    ASSERT_EQ(std::memcmp(&got, &expected, sizeof got), 0) << text << " read as " << got << ", expected " << expected;
  }
}

// Each joint's rotation is the normalized product of its channels' axis rotations, in channel order, as
// rotations.h composes them (the reader skips the product's zero terms and has its own sine).
TEST(BvhReader, RotationsAreTheProductOfTheChannelsAxisRotations) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-720.0, 720.0);
  const std::vector<std::string> orders = {"Xrotation Yrotation Zrotation", "Zrotation Xrotation Yrotation",
                                           "Yrotation Zrotation Xrotation", "Zrotation Yrotation Xrotation"};
  std::string bvh = "HIERARCHY\nROOT j0\n{\n  OFFSET 0 0 0\n  CHANNELS 3 " + orders[0] + "\n";
  for (size_t j = 1; j < orders.size(); ++j) {
    bvh += "JOINT j" + std::to_string(j) + "\n{\n  OFFSET 0 1 0\n  CHANNELS 3 " + orders[j] + "\n";
  }
  bvh += "End Site\n{\n  OFFSET 0 1 0\n}\n";
  for (size_t j = 0; j < orders.size(); ++j) bvh += "}\n";
  bvh += "MOTION\nFrames: 50\nFrame Time: 0.0333333\n";
  // Whole and half quarter turns and their neighbours, where the reader's sine changes quadrant; one too far
  // out for its reduction (libm's then); then random ones.
  const std::vector<double> chosen = {0.0,   90.0,  -90.0,     180.0,     -180.0,      270.0, 360.0, 540.0,
                                      -720.0, 45.0, -45.0,     135.0,     89.999999,   90.000001, 179.9999999,
                                      1e-12, -3e-9, -359.5,    719.99,    1e-300,      1e17};
  std::vector<double> degrees;
  size_t next_chosen = 0;
  for (int f = 0; f < 50; ++f) {
    for (size_t v = 0; v < 3 * orders.size(); ++v) {
      char text[32];
      const double value = next_chosen < chosen.size() ? chosen[next_chosen++] : angle(rng);
      const auto [end, ec] = std::to_chars(text, text + sizeof text, value);
      bvh += std::string(text, end) + " ";
      double parsed = 0.0;
      std::from_chars(text, end, parsed);
      degrees.push_back(parsed);
    }
    bvh += "\n";
  }
  const Clip clip = parse_bvh(bvh, "angles.bvh");
  const std::vector<std::array<int, 3>> axes = {{0, 1, 2}, {2, 0, 1}, {1, 2, 0}, {2, 1, 0}};
  for (int f = 0; f < 50; ++f) {
    for (int j = 0; j < 4; ++j) {
      const double* d = &degrees[static_cast<size_t>(f * 12 + j * 3)];
      const Quat expected = (axis_rotation(axes[j][0], d[0]) * axis_rotation(axes[j][1], d[1]) *
                             axis_rotation(axes[j][2], d[2])).normalized();
      const Quat got = clip.motion.rotation(f, j);
      // The reader's sine is within 2 ulp; rotations.h's turns the angle into radians first, rounding it by up
      // to half an ulp of 2 pi.
      for (int k = 0; k < 4; ++k) {
        ASSERT_NEAR(got.coeffs()[k], expected.coeffs()[k], 1e-15)
            << "frame " << f << " joint " << j << " coefficient " << k;
      }
    }
  }
}

TEST(BvhReader, IgnoresLinesAfterTheDeclaredFramesWithAWarning) {
  const Clip clip = parse_bvh(with_motion("MOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0 0 0 0 0 0 0\n1 1 1 1 1 1 1 1 1\n"),
                              "extra.bvh");
  EXPECT_EQ(clip.motion.frame_count, 1);
  ASSERT_EQ(clip.warnings.size(), 1u);
  EXPECT_NE(clip.warnings[0].find("ignored 1 line"), std::string::npos);
}

TEST(BvhReader, MissingFileIsAnInputError) {
  EXPECT_THROW(read_bvh("/nonexistent/dir/x.bvh"), InputError);
}

TEST(BvhRoundTrip, RandomSkeletonsAllOrders) {
  std::mt19937 rng(19);
  for (int trial = 0; trial < 10; ++trial) {
    Clip clip;
    clip.skeleton = testing::random_skeleton(rng, 3 + 5 * trial);
    clip.motion = testing::random_motion(rng, clip.skeleton, 7);
    const Clip back = parse_bvh(format_bvh(clip.skeleton, clip.motion), "random.bvh");
    ASSERT_EQ(back.skeleton.names, clip.skeleton.names);
    ASSERT_EQ(back.skeleton.parents, clip.skeleton.parents);
    for (int j = 0; j < clip.skeleton.joint_count(); ++j) {
      ASSERT_TRUE(back.skeleton.channels[j] == clip.skeleton.channels[j]);
    }
    const ClipDifference d = compare_clips(clip, back);
    EXPECT_LT(d.position, 1e-6) << "trial " << trial;
    EXPECT_LT(d.rotation, 1e-6) << "trial " << trial;
  }
}

TEST(BvhRoundTrip, ChangingTheEulerOrderKeepsTheMotion) {
  std::mt19937 rng(23);
  Clip clip;
  clip.skeleton = testing::random_skeleton(rng, 12);
  clip.motion = testing::random_motion(rng, clip.skeleton, 5);
  BvhWriteOptions options;
  options.euler_order = EulerOrder::XZY;
  const Clip back = parse_bvh(format_bvh(clip.skeleton, clip.motion, options), "order.bvh");
  for (const ChannelLayout& layout : back.skeleton.channels) EXPECT_EQ(layout.euler_order(), EulerOrder::XZY);
  const ClipDifference d = compare_clips(clip, back);
  EXPECT_LT(d.rotation, 1e-6);
  EXPECT_LT(d.position, 1e-6);
}

// Found by tests/fuzz: a joint with two rotation channels (Z then Y) came back
// as Ry * Rz when written with another Euler order, and 180 degrees off when
// its Y angle was beyond +-90 (the dropped X angle was 180).
TEST(BvhRoundTrip, KeepsJointsWithOneOrTwoRotationChannels) {
  const std::string text =
      "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n"
      "JOINT B\n{\nOFFSET 0 1 0\nCHANNELS 2 Zrotation Yrotation\n"
      "JOINT C\n{\nOFFSET 1 0 0\nCHANNELS 1 Xrotation\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\n}\n}\n"
      "MOTION\nFrames: 3\nFrame Time: 0.1\n10 20 30 30 40 50\n0 0 0 90 135 -170\n0 0 0 -100 -91 180\n";
  const Clip clip = parse_bvh(text, "few-channels.bvh");
  for (const std::optional<EulerOrder> order : {std::optional<EulerOrder>(), std::optional(EulerOrder::YXZ)}) {
    BvhWriteOptions options;
    options.euler_order = order;
    const Clip back = parse_bvh(format_bvh(clip.skeleton, clip.motion, options), "few-channels (rewritten).bvh");
    EXPECT_EQ(back.skeleton.channels[0].euler_order(), order.value_or(EulerOrder::XYZ));
    const ClipDifference d = compare_clips(clip, back);
    EXPECT_LT(d.rotation, 1e-6) << "max rotation difference (rad) " << d.rotation;
    EXPECT_LT(d.position, 1e-6) << "max relative position difference " << d.position;
  }
}

void expect_round_trip(const std::string& path) {
  const Clip clip = read_bvh(path);
  const Clip back = parse_bvh(format_bvh(clip.skeleton, clip.motion), path + " (rewritten)");
  ASSERT_EQ(back.skeleton.names, clip.skeleton.names) << path;
  ASSERT_EQ(back.motion.frame_count, clip.motion.frame_count) << path;
  EXPECT_NEAR(back.motion.fps, clip.motion.fps, 1e-5 * clip.motion.fps) << path;
  const ClipDifference d = compare_clips(clip, back);
  EXPECT_LT(d.position, 1e-5) << path << ": relative position difference " << d.position;
  EXPECT_LT(d.rotation, 1e-5) << path << ": rotation difference (rad) " << d.rotation;
}

TEST(BvhRoundTrip, DebianCmuFiles) {
  const auto files = testing::bvh_files_under(testing::cmu_bvh_dir());
  ASSERT_EQ(files.size(), 3u) << "run scripts/setup.sh (assimp-testmodels) first";
  for (const auto& path : files) expect_round_trip(path);
}

TEST(BvhRoundTrip, SharedDataSample) {
  const auto files = testing::bvh_files_under(testing::shared_data_dir());
  if (files.empty()) GTEST_SKIP() << "../shared/data not present";
  // Every 10th file keeps the unit suite quick; `nec` reads them all in the demo.
  for (size_t i = 0; i < files.size(); i += 10) expect_round_trip(files[i]);
}

}  // namespace
}  // namespace nec
