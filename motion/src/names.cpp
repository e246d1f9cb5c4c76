// Canonical joint names: word splitting, side markers, synonyms.
#include "nec/motion/names.h"

#include <algorithm>
#include <cctype>
#include <unordered_map>
#include <unordered_set>

namespace nec {
namespace {

bool is_lower(char c) { return std::islower(static_cast<unsigned char>(c)) != 0; }
bool is_upper(char c) { return std::isupper(static_cast<unsigned char>(c)) != 0; }
bool is_alpha(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0; }

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Rig prefixes that carry no meaning.
const std::unordered_set<std::string>& noise_words() {
  static const std::unordered_set<std::string> words = {
      "bip", "bip01", "mixamorig", "joint", "jnt", "bone", "def", "org", "mch", "b", "j", "bn", "bvh", "c"};
  return words;
}

// Single words mapped to one or more canonical words.
const std::unordered_map<std::string, std::string>& synonyms() {
  static const std::unordered_map<std::string, std::string> map = {
      {"thigh", "upper leg"},     {"upleg", "upper leg"},   {"femur", "upper leg"},
      {"calf", "lower leg"},      {"shin", "lower leg"},    {"knee", "lower leg"},
      {"tibia", "lower leg"},     {"ankle", "foot"},        {"toes", "toe"},
      {"toebase", "toe"},         {"forearm", "lower arm"}, {"elbow", "lower arm"},
      {"upperarm", "upper arm"},  {"humerus", "upper arm"}, {"clavicle", "shoulder"},
      {"collar", "shoulder"},     {"scapula", "shoulder"},  {"wrist", "hand"},
      {"palm", "hand"},           {"pelvis", "hips"},       {"hip", "hips"},
      {"root", "hips"},           {"abdomen", "spine"},     {"ab", "spine"},
      {"chest", "chest"},         {"torso", "spine"},       {"thorax", "chest"},
      {"skull", "head"},          {"cranium", "head"},      {"jaw", "jaw"},
      {"cervical", "neck"},       {"tailbone", "tail"},     {"coccyx", "tail"},
      {"pinky", "little finger"}, {"thumb", "thumb"},       {"index", "index finger"},
      {"middle", "middle finger"}, {"ring", "ring finger"}, {"fingers", "finger"},
      {"phalange", "finger"},     {"wing", "wing"},         {"feather", "wing"},
      {"flipper", "fin"},         {"tentacle", "tentacle"}, {"leg", "leg"},
      {"arm", "arm"},             {"hand", "hand"},         {"foot", "foot"},
      {"spine", "spine"},         {"neck", "neck"},         {"head", "head"},
      {"tail", "tail"},           {"toe", "toe"},           {"hips", "hips"},
  };
  return map;
}

// Words that mark a side, alone or as a prefix/suffix letter.
Side side_of_word(const std::string& w) {
  if (w == "l" || w == "left" || w == "lft" || w == "lt") return Side::Left;
  if (w == "r" || w == "right" || w == "rgt" || w == "rt") return Side::Right;
  return Side::None;
}

// "upper"/"lower"/"up"/"low" followed by a limb become one canonical phrase.
std::vector<std::string> merge_qualifiers(const std::vector<std::string>& words) {
  std::vector<std::string> out;
  for (size_t i = 0; i < words.size(); ++i) {
    const std::string& w = words[i];
    const bool has_next = i + 1 < words.size();
    if ((w == "up" || w == "upper") && has_next && (words[i + 1] == "leg" || words[i + 1] == "arm")) {
      out.push_back("upper " + words[++i]);
    } else if ((w == "low" || w == "lower" || w == "fore") && has_next &&
               (words[i + 1] == "leg" || words[i + 1] == "arm")) {
      out.push_back("lower " + words[++i]);
    } else {
      out.push_back(w);
    }
  }
  return out;
}

}  // namespace

std::vector<std::string> split_joint_name(std::string_view name) {
  std::vector<std::string> words;
  std::string current;
  auto flush = [&] {
    if (!current.empty()) words.push_back(lower(current));
    current.clear();
  };
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (!is_alpha(c)) {
      flush();  // separators and digits end a word; digits carry no meaning here
      continue;
    }
    if (!current.empty()) {
      const char prev = current.back();
      const bool camel = is_lower(prev) && is_upper(c);
      // "HTMLParser" style: an upper followed by upper+lower starts a word.
      const bool acronym_end = is_upper(prev) && is_upper(c) && i + 1 < name.size() && is_lower(name[i + 1]);
      if (camel || acronym_end) flush();
    }
    current += c;
  }
  flush();
  return words;
}

Side joint_side(std::string_view name) {
  for (const std::string& w : split_joint_name(name)) {
    const Side side = side_of_word(w);
    if (side != Side::None) return side;
  }
  // "Lhand", "RFoot" style: a leading L/R directly before an upper-case letter.
  if (name.size() >= 2 && is_upper(name[1])) {
    if (name[0] == 'L') return Side::Left;
    if (name[0] == 'R') return Side::Right;
  }
  return Side::None;
}

std::string canonical_joint_name(std::string_view name) {
  std::vector<std::string> words = split_joint_name(name);
  Side side = joint_side(name);
  // Leading L/R glued to a word ("LHipJoint" splits as "lhip", "joint").
  if (!words.empty() && name.size() >= 2 && is_upper(name[1]) && (name[0] == 'L' || name[0] == 'R') &&
      words[0].size() > 1 && side_of_word(words[0]) == Side::None) {
    words[0] = words[0].substr(1);
  }
  std::vector<std::string> kept;
  for (const std::string& w : words) {
    if (side_of_word(w) != Side::None) continue;
    if (noise_words().count(w)) continue;
    const auto it = synonyms().find(w);
    kept.push_back(it != synonyms().end() ? it->second : w);
  }
  kept = merge_qualifiers(kept);
  // Collapse repeated words ("spine spine").
  kept.erase(std::unique(kept.begin(), kept.end()), kept.end());
  std::string out;
  if (side == Side::Left) out = "left";
  if (side == Side::Right) out = "right";
  for (const std::string& w : kept) {
    if (!out.empty()) out += ' ';
    out += w;
  }
  if (kept.empty()) out += out.empty() ? "joint" : " joint";
  return out;
}

std::string mirrored_canonical_name(const std::string& canonical) {
  if (canonical.rfind("left", 0) == 0) return "right" + canonical.substr(4);
  if (canonical.rfind("right", 0) == 0) return "left" + canonical.substr(5);
  return canonical;
}

}  // namespace nec
