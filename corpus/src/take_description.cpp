// Take descriptions (CMU's free text) -> parts with verb phrases and activity kinds -> clip captions.
#include "nec/corpus/take_description.h"

#include "plain_text.h"

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>

namespace nec {
namespace {

// Base forms of the verbs descriptions of human and animal takes use.
const std::set<std::string>& verbs() {
  static const std::set<std::string> words = {
      "balance", "bend",  "bow",   "box",    "carry",  "catch",   "clap",   "climb", "crawl", "dance",
      "dangle",  "direct", "dive", "drink", "dribble", "eat",   "fall",    "fold",   "get",   "grab",  "hang",
      "hop",     "jog",   "jump",  "kick",   "kneel",  "laugh",   "leap",   "lie",   "lift",  "limp",
      "look",    "lower", "march", "navigate", "pick", "play",    "point",  "pull",  "punch", "push",
      "put",     "raise", "reach", "rise",   "rock",   "roll",    "run",    "scoop", "screw", "shake",
      "shoot",   "shuffle", "sit", "skip",   "sneak",  "spin",    "sprint", "squat", "stand", "step",
      "stomp",   "stretch", "stride", "strike", "sweep", "swim",  "swing",  "throw", "tiptoe", "turn",
      "twist",   "unscrew", "walk", "wash",   "wave",   "wipe"};
  return words;
}

// Adjectives before a verb noun ("slow walk", "forward jump") and the adverbs they become.
const std::map<std::string, std::string>& adverbs() {
  static const std::map<std::string, std::string> words = {
      {"slow", "slowly"},     {"brisk", "briskly"},   {"quick", "quickly"},   {"fast", "fast"},
      {"forward", "forward"}, {"backward", "backward"}, {"backwards", "backward"}, {"sideways", "sideways"},
      {"around", "around"}};
  return words;
}

// Exercises named by a noun that a verb would misread ("jumping jacks" is not jumping at jacks).
const std::set<std::string>& exercises() {
  static const std::set<std::string> names = {"jumping jacks", "squats", "side twists", "push-ups", "sit-ups",
                                              "lunges", "crunches"};
  return names;
}

// Words that make a verbless part a detail of the one before it ("ankle on other knee", "arms held high").
const std::set<std::string>& body_words() {
  static const std::set<std::string> words = {"ankle", "ankles", "arm", "arms", "back", "body", "chin", "elbow",
                                              "elbows", "foot", "feet", "hand", "hands", "head", "hip", "hips",
                                              "knee", "knees", "leg", "legs", "shoulder", "shoulders"};
  return words;
}

// Themes that read better as their own verb phrase than as "does <theme>".
const std::map<std::string, std::string>& theme_phrases() {
  static const std::map<std::string, std::string> phrases = {
      {"dance", "dances"},           {"basketball", "plays basketball"}, {"soccer", "plays soccer"},
      {"football", "plays football"}, {"playground", "plays on a playground"}, {"navigate", "moves around"},
      {"boxing", "boxes"},            {"martial arts", "does martial arts"}};
  return phrases;
}

std::string lower_trimmed(std::string_view s) { return detail::lower(detail::trim(s)); }

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> out;
  size_t begin = 0;
  while (begin <= text.size()) {
    const size_t end = std::min(text.find(separator, begin), text.size());
    const std::string piece = lower_trimmed(text.substr(begin, end - begin));
    if (!piece.empty()) out.push_back(piece);
    begin = end + 1;
  }
  return out;
}

std::string join_words(const std::vector<std::string>& words, size_t begin, size_t end) {
  std::string out;
  for (size_t i = begin; i < end; ++i) out += (out.empty() ? "" : " ") + words[i];
  return out;
}

std::string third_person(const std::string& verb) {
  if (verb == "do" || verb == "go") return verb + "es";
  const auto ends = [&](const char* suffix) {
    const std::string s(suffix);
    return verb.size() >= s.size() && verb.compare(verb.size() - s.size(), s.size(), s) == 0;
  };
  if (ends("s") || ends("sh") || ends("ch") || ends("x") || ends("z")) return verb + "es";
  if (verb.size() > 1 && verb.back() == 'y' && std::string("aeiou").find(verb[verb.size() - 2]) == std::string::npos) {
    return verb.substr(0, verb.size() - 1) + "ies";
  }
  return verb + "s";
}

bool is_verb(const std::string& word) { return verbs().count(word) > 0; }

// The base form of a gerund ("folding" -> "fold", "dribbling" -> "dribble", "running" -> "run"), "" if none.
std::string gerund_stem(const std::string& word) {
  if (word.size() < 5 || word.compare(word.size() - 3, 3, "ing") != 0) return "";
  const std::string base = word.substr(0, word.size() - 3);
  if (is_verb(base)) return base;
  if (is_verb(base + "e")) return base + "e";
  if (base.size() > 2 && base.back() == base[base.size() - 2] && is_verb(base.substr(0, base.size() - 1))) {
    return base.substr(0, base.size() - 1);
  }
  return "";
}

// A verb noun, singular ("jumps" -> "jump"), "" if the word is none.
std::string verb_noun(const std::string& word) {
  if (is_verb(word)) return word;
  if (word.size() > 1 && word.back() == 's' && is_verb(word.substr(0, word.size() - 1))) {
    return word.substr(0, word.size() - 1);
  }
  return "";
}

bool has_direction(const std::vector<std::string>& words) {
  return std::any_of(words.begin(), words.end(), [](const std::string& w) {
    return w == "forward" || w == "backward" || w == "backwards" || w == "sideways";
  });
}

DescribedKind kind_of(const std::string& verb, const std::vector<std::string>& words) {
  static const std::set<std::string> travel = {"walk", "stride", "jog", "run", "sprint", "navigate", "march"};
  static const std::set<std::string> jump = {"jump", "hop", "leap"};
  static const std::set<std::string> low = {"sit", "lie", "lower", "kneel"};
  const bool up = std::find(words.begin(), words.end(), "up") != words.end();
  if (travel.count(verb) || ((verb == "dribble" || verb == "step") && has_direction(words))) {
    return DescribedKind::Travel;
  }
  if (jump.count(verb)) return DescribedKind::Jump;
  if (low.count(verb) || verb == "rise" || ((verb == "stand" || verb == "get") && up)) return DescribedKind::Low;
  return DescribedKind::InPlace;
}

enum class PartRole { Action, Detail };

struct ReadPart {
  std::string phrase;
  DescribedKind kind = DescribedKind::InPlace;
  PartRole role = PartRole::Action;
};

// One variant of a part (no alternatives left) -> its phrase, kind and role.
ReadPart read_variant(const std::string& text) {
  std::vector<std::string> words = split(text, ' ');
  for (std::string& w : words) {
    if (w == "self") w = "oneself";
  }
  const std::string rest = join_words(words, 1, words.size());
  const auto with_rest = [&](const std::string& verb) { return rest.empty() ? verb : verb + " " + rest; };
  if (exercises().count(join_words(words, 0, words.size()))) {
    return {"does " + join_words(words, 0, words.size()), DescribedKind::InPlace, PartRole::Action};
  }
  if (is_verb(words[0])) return {with_rest(third_person(words[0])), kind_of(words[0], words), PartRole::Action};
  if (const std::string stem = gerund_stem(words[0]); !stem.empty()) {
    return {with_rest(third_person(stem)), kind_of(stem, words), PartRole::Action};
  }
  const bool all_adverbs = std::all_of(words.begin(), words.end(), [](const std::string& w) { return adverbs().count(w) > 0; });
  if (all_adverbs) return {join_words(words, 0, words.size()), DescribedKind::InPlace, PartRole::Detail};
  // "forward jump", "slow walk": adjectives before a verb noun.
  if (const std::string verb = verb_noun(words.back()); !verb.empty()) {
    const bool modifiers = std::all_of(words.begin(), words.end() - 1,
                                       [](const std::string& w) { return adverbs().count(w) > 0; });
    if (modifiers) {
      std::string phrase = third_person(verb);
      for (size_t i = 0; i + 1 < words.size(); ++i) phrase += " " + adverbs().at(words[i]);
      return {phrase, kind_of(verb, words), PartRole::Action};
    }
  }
  const bool about_the_body = std::any_of(words.begin(), words.end(), [](const std::string& w) {
    return body_words().count(w) > 0;
  });
  const std::string whole = join_words(words, 0, words.size());
  if (about_the_body) {
    // A detail cut short ("legs push off against") says nothing a caption could keep.
    static const std::set<std::string> dangling = {"against", "at", "for", "from", "in", "into", "of", "off",
                                                   "on", "onto", "to", "with"};
    if (dangling.count(words.back())) return {"", DescribedKind::InPlace, PartRole::Detail};
    return {"with " + whole, DescribedKind::InPlace, PartRole::Detail};
  }
  const bool leaps = std::any_of(words.begin(), words.end(), [](const std::string& w) { return w.rfind("jete", 0) == 0; });
  return {"does " + whole, leaps ? DescribedKind::Jump : DescribedKind::InPlace, PartRole::Action};
}

// A part's variants: each word written "a/b" gives one variant per alternative ("run/jog" -> run, jog).
std::vector<std::string> variants(const std::string& text) {
  std::vector<std::string> words = split(text, ' ');
  size_t count = 1;
  for (const std::string& w : words) count = std::max(count, split(w, '/').size());
  std::vector<std::string> out;
  for (size_t v = 0; v < count; ++v) {
    std::string variant;
    for (const std::string& w : words) {
      const std::vector<std::string> choices = split(w, '/');
      const std::string& pick = choices.empty() ? w : choices[std::min(v, choices.size() - 1)];
      variant += (variant.empty() ? "" : " ") + pick;
    }
    if (std::find(out.begin(), out.end(), variant) == out.end()) out.push_back(variant);
  }
  return out;
}

std::string theme_phrase(const std::string& theme) {
  const auto it = theme_phrases().find(theme);
  if (it != theme_phrases().end()) return it->second;
  const std::vector<std::string> words = split(theme, ' ');
  if (!words.empty() && is_verb(words[0])) return read_variant(theme).phrase;
  return "does " + theme;
}

// "a", "a and b", "a, b and c".
std::string list_phrase(const std::vector<std::string>& items) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += i + 1 == items.size() ? " and " : ", ";
    out += items[i];
  }
  return out;
}

double travel_share(const Segment& clip) {
  int travel = 0;
  for (const Phase& p : clip.phases) {
    if (p.activity == Activity::Walk || p.activity == Activity::Trot || p.activity == Activity::Run) {
      travel += p.end - p.begin;
    }
  }
  return clip.end > clip.begin ? static_cast<double>(travel) / (clip.end - clip.begin) : 0.0;
}

}  // namespace

TakeDescription parse_take_description(std::string_view text) {
  TakeDescription out;
  out.text = std::string(text);
  std::string body = lower_trimmed(text);
  if (const size_t dash = body.find(" - "); dash != std::string::npos) {
    out.theme = lower_trimmed(body.substr(0, dash));
    body = lower_trimmed(body.substr(dash + 3));
  }
  for (const std::string& piece : split(body, ',')) {
    DescribedPart part;
    part.text = piece;
    PartRole role = PartRole::Action;
    for (const std::string& variant : variants(piece)) {
      const ReadPart read = read_variant(variant);
      if (part.phrases.empty()) {
        part.kind = read.kind;
        role = read.role;
      }
      if (std::find(part.phrases.begin(), part.phrases.end(), read.phrase) == part.phrases.end()) {
        part.phrases.push_back(read.phrase);
      }
    }
    if (part.phrases.front().empty()) continue;  // a dangling detail
    if (role == PartRole::Detail && !out.parts.empty()) {
      for (std::string& phrase : out.parts.back().phrases) phrase += ", " + part.phrases.front();
      out.parts.back().text += ", " + piece;
      continue;
    }
    if (role == PartRole::Detail) part.phrases = {"moves " + part.phrases.front()};
    out.parts.push_back(std::move(part));
  }
  if (out.parts.empty() && out.theme.empty()) {
    throw std::invalid_argument("take description '" + out.text + "' has no words");
  }
  return out;
}

bool part_agrees(const TakeDescription& description, const DescribedPart& part, const Segment& clip) {
  const auto has_phase = [&](std::initializer_list<Activity> activities) {
    return std::any_of(clip.phases.begin(), clip.phases.end(), [&](const Phase& p) {
      return std::find(activities.begin(), activities.end(), p.activity) != activities.end();
    });
  };
  switch (part.kind) {
    case DescribedKind::Travel:
      return travel_share(clip) >= 1.0 / 3.0;
    case DescribedKind::Jump:
      return clip.jumps || has_phase({Activity::Jump});
    case DescribedKind::Low:
      return has_phase({Activity::Sit, Activity::Lie});
    case DescribedKind::InPlace: {
      const bool names_travel = std::any_of(description.parts.begin(), description.parts.end(),
                                            [](const DescribedPart& p) { return p.kind == DescribedKind::Travel; });
      return !names_travel || travel_share(clip) < 0.5;
    }
  }
  return false;
}

std::vector<std::string> described_clip_captions(const TakeDescription& description, const Segment& clip,
                                                 std::string_view noun, bool whole_take) {
  std::vector<const DescribedPart*> agreeing;
  for (const DescribedPart& part : description.parts) {
    if (whole_take || part_agrees(description, part, clip)) agreeing.push_back(&part);
  }
  const std::string subject = indefinite_article(noun) + " " + std::string(noun);
  const std::string theme = description.theme.empty() ? "" : theme_phrase(description.theme);
  if (agreeing.empty()) return theme.empty() ? std::vector<std::string>{} : std::vector<std::string>{subject + " " + theme};
  std::vector<std::string> canonical, alternative;
  for (const DescribedPart* part : agreeing) {
    canonical.push_back(part->phrases.front());
    alternative.push_back(part->phrases.back());
  }
  std::vector<std::string> captions = {subject + " " + list_phrase(canonical), "the " + std::string(noun) + " " + list_phrase(alternative)};
  if (!theme.empty()) captions.push_back(subject + " " + theme + " and " + list_phrase(canonical));
  return captions;
}

}  // namespace nec
