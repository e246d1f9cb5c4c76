// Joint names (body_plans.h): the word of each part in every naming style
// (Mixamo, Blender, game, 3ds Max Biped, Maya, Truebones), each mapping to a meaningful
// canonical name, and the joint specs that body plans describe joints with.
#include "body_plans.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace nec::zoo::detail {
namespace {

// The word of a part in each naming style. Every word maps to a meaningful
// canonical name (nec::canonical_joint_name): thigh/UpLeg -> "upper leg",
// calf/shin -> "lower leg", clavicle -> "shoulder", pelvis -> "hips",
// abdomen -> "spine", thorax -> "chest", forearm -> "lower arm".
struct PartWords {
  const char* mixamo;
  const char* blender;
  const char* game;
  const char* biped3ds;
};

PartWords part_words(Part part) {
  switch (part) {
    case Part::Hips: return {"Hips", "hips", "pelvis", "Pelvis"};
    case Part::Thorax: return {"Thorax", "thorax", "thorax", "Thorax"};
    case Part::Spine: return {"Spine", "spine", "spine", "Spine"};
    case Part::Abdomen: return {"Abdomen", "abdomen", "abdomen", "Abdomen"};
    case Part::Neck: return {"Neck", "neck", "neck", "Neck"};
    case Part::Head: return {"Head", "head", "head", "Head"};
    case Part::Jaw: return {"Jaw", "jaw", "jaw", "Jaw"};
    case Part::Mandible: return {"Mandible", "mandible", "mandible", "Mandible"};
    case Part::Fang: return {"Fang", "fang", "fang", "Fang"};
    case Part::Tail: return {"Tail", "tail", "tail", "Tail"};
    case Part::Shoulder: return {"Shoulder", "shoulder", "clavicle", "Clavicle"};
    case Part::UpperArm: return {"Arm", "upper_arm", "upperarm", "UpperArm"};
    case Part::ForeArm: return {"ForeArm", "forearm", "forearm", "Forearm"};
    case Part::Hand: return {"Hand", "hand", "hand", "Hand"};
    case Part::Coxa: return {"Coxa", "coxa", "coxa", "Coxa"};
    case Part::UpperLeg: return {"UpLeg", "thigh", "thigh", "Thigh"};
    case Part::LowerLeg: return {"Leg", "shin", "calf", "Calf"};
    case Part::Foot: return {"Foot", "foot", "foot", "Foot"};
    case Part::Toe: return {"ToeBase", "toe", "toe", "Toe"};
    case Part::WingArm: return {"WingArm", "wing_upper_arm", "wing_upperarm", "Wing UpperArm"};
    case Part::WingForeArm: return {"WingForeArm", "wing_forearm", "wing_forearm", "Wing Forearm"};
    case Part::WingHand: return {"WingHand", "wing_hand", "wing_hand", "Wing Hand"};
    case Part::WingFinger: return {"WingFinger", "wing_finger", "wing_finger", "Wing Finger"};
    case Part::Fin: return {"Fin", "fin", "fin", "Fin"};
    case Part::Antenna: return {"Antenna", "antenna", "antenna", "Antenna"};
    case Part::Palp: return {"Palp", "palp", "palp", "Palp"};
    case Part::Claw: return {"Claw", "claw", "claw", "Claw"};
    case Part::Hoof: return {"Hoof", "hoof", "hoof", "Hoof"};
    case Part::Trunk: return {"Trunk", "trunk", "trunk", "Trunk"};
  }
  return {"Joint", "joint", "joint", "Joint"};
}

// "Wing UpperArm" -> "WingUpperArm".
std::string without_spaces(std::string word) {
  word.erase(std::remove(word.begin(), word.end(), ' '), word.end());
  return word;
}

bool is_leg_part(Part part) {
  return part == Part::Coxa || part == Part::UpperLeg || part == Part::LowerLeg || part == Part::Foot ||
         part == Part::Toe;
}

std::string capitalized(std::string word) {
  if (!word.empty()) word[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(word[0])));
  return word;
}

}  // namespace

JointSpec spec(Part part, Side side, std::string qualifier) {
  JointSpec s;
  s.part = part;
  s.side = side;
  s.qualifier = std::move(qualifier);
  return s;
}

std::vector<JointSpec> chain_specs(Part part, int count, Side side, const std::string& qualifier) {
  std::vector<JointSpec> specs;
  for (int k = 0; k < count; ++k) {
    JointSpec s = spec(part, side, qualifier);
    s.index = k;
    specs.push_back(s);
  }
  return specs;
}

std::string joint_name(const JointSpec& joint, NamingStyle style) {
  const PartWords words = part_words(joint.part);
  const bool left = joint.side == Side::Left;
  const bool sided = joint.side != Side::None;
  std::string name;
  switch (style) {
    case NamingStyle::Mixamo:  // LeftFrontUpLeg, Spine2, LeftUpLeg3, LeftPectoralFin1
      if (sided) name = left ? "Left" : "Right";
      name += capitalized(joint.qualifier) + words.mixamo;
      if (joint.pair > 0) name += std::to_string(joint.pair);
      if (joint.index > 0) name += (joint.pair > 0 ? "_" : "") + std::to_string(joint.index);
      return name;
    case NamingStyle::Blender:  // front_thigh.L, spine.002, thigh.L.003, antenna.L.001
      if (!joint.qualifier.empty()) name = joint.qualifier + "_";
      name += words.blender;
      if (sided) name += left ? ".L" : ".R";
      if (joint.pair > 0) name += fmt::format(".{:03d}", joint.pair);
      if (joint.index > 0) name += fmt::format(".{:03d}", joint.index);
      return name;
    case NamingStyle::Game:  // front_thigh_l, spine_02, leg_l_03_02, pectoral_fin_r_01
      if (joint.pair > 0 && is_leg_part(joint.part)) {
        return fmt::format("leg_{}_{:02d}_{:02d}", left ? "l" : "r", joint.pair, joint.segment + 1);
      }
      if (!joint.qualifier.empty()) name = joint.qualifier + "_";
      name += words.game;
      if (sided) name += left ? "_l" : "_r";
      if (joint.pair > 0) name += fmt::format("_{:02d}", joint.pair);
      if (joint.index >= 0) name += fmt::format("_{:02d}", joint.index + 1);
      return name;
    case NamingStyle::Biped3ds:  // Bip01 L Front Thigh, Bip01 Spine2, Bip01 L Thigh3
      name = "Bip01";
      if (sided) name += left ? " L" : " R";
      if (!joint.qualifier.empty()) name += " " + capitalized(joint.qualifier);
      name += std::string(" ") + words.biped3ds;
      if (joint.pair > 0) name += std::to_string(joint.pair);
      if (joint.index > 0) name += (joint.pair > 0 ? " " : "") + std::to_string(joint.index);
      return name;
    case NamingStyle::Maya:  // L_front_thigh_JNT, C_spine_02_JNT, L_leg_03_02_JNT
      name = sided ? (left ? "L_" : "R_") : "C_";
      if (joint.pair > 0 && is_leg_part(joint.part)) {
        return name + fmt::format("leg_{:02d}_{:02d}_JNT", joint.pair, joint.segment + 1);
      }
      if (!joint.qualifier.empty()) name += joint.qualifier + "_";
      name += words.blender;
      if (joint.pair > 0) name += fmt::format("_{:02d}", joint.pair);
      if (joint.index >= 0) name += fmt::format("_{:02d}", joint.index + 1);
      return name + "_JNT";
    case NamingStyle::Truebones:  // BN_FrontThigh_L, BN_Spine02, BN_Leg_L_03_02
      name = "BN_";
      if (joint.pair > 0 && is_leg_part(joint.part)) {
        return name + fmt::format("Leg_{}_{:02d}_{:02d}", left ? "L" : "R", joint.pair, joint.segment + 1);
      }
      name += capitalized(joint.qualifier) + without_spaces(words.biped3ds);
      if (joint.pair > 0) name += fmt::format("{:02d}", joint.pair);
      if (joint.index >= 0) name += fmt::format("{:02d}", joint.index + 1);
      if (sided) name += left ? "_L" : "_R";
      return name;
    case NamingStyle::Numbered:
      break;
  }
  throw std::logic_error("joint_name: Numbered names are assigned by index");
}

}  // namespace nec::zoo::detail
