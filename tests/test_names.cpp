// Canonical joint names.
#include "nec/motion/names.h"

#include <gtest/gtest.h>

namespace nec {
namespace {

TEST(Names, CanonicalNamesAcrossConventions) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"LeftUpLeg", "left upper leg"},   {"thigh.L", "left upper leg"},      {"Bip01 R Thigh", "right upper leg"},
      {"leg_l_01", "left leg"},          {"UpperArm_L", "left upper arm"},   {"RightForeArm", "right lower arm"},
      {"LowerArm_R", "right lower arm"}, {"joint12", "joint"},               {"mixamorig:LeftHand", "left hand"},
      {"Hips", "hips"},                  {"LHipJoint", "left hips"},         {"Tail1", "tail"},
      {"Neck", "neck"},                  {"RightShoulder", "right shoulder"}, {"l_wing_02", "left wing"},
      {"LTHUMB", "left thumb"},          {"Spine1", "spine"},                {"HEAD", "head"},
  };
  for (const auto& [name, expected] : cases) EXPECT_EQ(canonical_joint_name(name), expected) << name;
}

TEST(Names, SplitAndSide) {
  EXPECT_EQ(split_joint_name("LeftToeBase"), (std::vector<std::string>{"left", "toe", "base"}));
  EXPECT_EQ(split_joint_name("spine_03.def"), (std::vector<std::string>{"spine", "def"}));
  EXPECT_EQ(joint_side("Shoulder_R"), Side::Right);
  EXPECT_EQ(joint_side("LFoot"), Side::Left);
  EXPECT_EQ(joint_side("Leg"), Side::None);
  EXPECT_EQ(joint_side("Root"), Side::None);
}

TEST(Names, Mirror) {
  EXPECT_EQ(mirrored_canonical_name("left upper arm"), "right upper arm");
  EXPECT_EQ(mirrored_canonical_name("right foot"), "left foot");
  EXPECT_EQ(mirrored_canonical_name("tail"), "tail");
}

}  // namespace
}  // namespace nec
