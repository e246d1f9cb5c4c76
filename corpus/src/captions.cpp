// Captions from sidecar text files, CSV tables and Bandai Namco labels.
#include "nec/corpus/captions.h"

#include "plain_text.h"

#include "nec/motion/clip_file.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <stdexcept>

namespace nec {
namespace {

namespace fs = std::filesystem;

constexpr size_t kMaxTextBytes = size_t{64} << 20;  // captions, tables and label files

using detail::lower;
using detail::trim;

std::string_view strip_bom(std::string_view text) {
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  return text;
}

// Calls visit(line_number, line) for every line, without '\n' or a trailing '\r'.
template <typename Visit>
void for_each_line(std::string_view text, Visit visit) {
  long number = 0;
  while (!text.empty()) {
    const size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    visit(++number, line);
    if (end == std::string_view::npos) break;
    text.remove_prefix(end + 1);
  }
}

// The key under which tables store a path: absolute, normalized, symlinks resolved where they exist.
std::string path_key(const fs::path& path) {
  std::error_code ec;
  fs::path resolved = fs::weakly_canonical(path, ec);
  if (ec) resolved = fs::absolute(path, ec).lexically_normal();
  return resolved.string();
}

// One CSV record of a single physical line: fields, quotes removed.
std::vector<std::string> split_csv_line(std::string_view line, const std::string& csv_path, long line_number) {
  std::vector<std::string> fields;
  size_t i = 0;
  while (true) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::string field;
    if (i < line.size() && line[i] == '"') {
      ++i;
      bool closed = false;
      while (i < line.size()) {
        if (line[i] == '"') {
          if (i + 1 < line.size() && line[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          closed = true;
          ++i;
          break;
        }
        field += line[i++];
      }
      if (!closed) throw InputError(csv_path, line_number, "unterminated quoted field");
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
      if (i < line.size() && line[i] != ',') {
        throw InputError(csv_path, line_number, "unexpected text after a closing quote");
      }
    } else {
      const size_t comma = line.find(',', i);
      const std::string_view raw = line.substr(i, comma == std::string_view::npos ? std::string_view::npos : comma - i);
      if (raw.find('"') != std::string_view::npos) {
        throw InputError(csv_path, line_number,
                         "a quote inside an unquoted field; quote the whole field and double the quote (\"\")");
      }
      field = std::string(trim(raw));
      i = comma == std::string_view::npos ? line.size() : comma;
    }
    fields.push_back(std::move(field));
    if (i >= line.size()) break;
    ++i;  // the comma
  }
  return fields;
}

// Columns of a table: which field names the file and which holds the caption.
struct Columns {
  size_t count = 2;
  size_t file = 0;
  size_t caption = 1;
};

// The columns a header row names (`file,caption`, `path,text`, `file,description,subject`, ...); nullopt for a
// row that is not a header.
std::optional<Columns> header_columns(const std::vector<std::string>& fields) {
  static const std::array<const char*, 4> file_names = {"file", "path", "filename", "bvh"};
  static const std::array<const char*, 3> caption_names = {"caption", "text", "description"};
  const auto column = [&](const auto& names) -> std::optional<size_t> {
    for (size_t i = 0; i < fields.size(); ++i) {
      if (std::find(names.begin(), names.end(), lower(fields[i])) != names.end()) return i;
    }
    return std::nullopt;
  };
  const auto file = column(file_names);
  const auto caption = column(caption_names);
  if (!file || !caption) return std::nullopt;
  return Columns{fields.size(), *file, *caption};
}

// ---------------------------------------------------------------------------
// Bandai vocabulary.

// A content: verb phrases in the third person, canonical first.
struct ContentPhrases {
  const char* label;
  std::array<const char*, 3> verbs;
};

// A style: adverbials (canonical first; "" for none) and a subject phrase.
struct StylePhrases {
  const char* label;
  std::array<const char*, 3> adverbials;
  const char* subject;
};

// Phrasings follow what the takes show: set 1's walk-left/right walk forward
// with a sideways drift to that side (to the left of the capture space),
// bye waves one hand, byebye both, respond raises one hand above the head,
// slash swings both hands together.
const std::vector<ContentPhrases>& content_phrases() {
  static const std::vector<ContentPhrases> table = {
      {"walk", {"walks forward", "walks", "walks straight ahead"}},
      {"run", {"runs forward", "runs", "runs straight ahead"}},
      {"dash", {"dashes forward", "sprints", "runs at full speed"}},
      {"walk-back", {"walks backward", "walks backwards", "steps backward"}},
      {"walk-left", {"walks to the left", "walks leftward", "walks forward and to the left"}},
      {"walk-right", {"walks to the right", "walks rightward", "walks forward and to the right"}},
      {"bow", {"bows", "bows politely", "takes a bow"}},
      {"bye", {"waves goodbye", "waves goodbye with one hand", "waves to say goodbye"}},
      {"guide", {"gestures to guide someone", "shows the way with a hand", "guides someone with a hand gesture"}},
      {"byebye", {"waves goodbye with both hands", "waves both hands to say goodbye", "says bye-bye with both hands"}},
      {"respond", {"raises a hand to respond", "responds by raising a hand", "raises a hand in reply"}},
      {"call", {"calls out to someone", "calls someone over", "calls out loudly to someone"}},
      {"punch", {"punches", "throws punches", "punches forward"}},
      {"kick", {"kicks", "kicks with a leg", "throws a kick"}},
      {"slash", {"slashes with a sword", "swings a sword", "makes slashing strikes with a sword"}},
      {"dance-long", {"dances", "performs a long dance", "dances for a while"}},
      {"dance-short", {"does a short dance", "performs a short dance", "dances briefly"}},
      {"walk-turn-left", {"walks and turns left", "walks, turning to the left", "turns left while walking"}},
      {"walk-turn-right", {"walks and turns right", "walks, turning to the right", "turns right while walking"}},
      {"wave-both-hands", {"waves both hands", "waves with both hands", "waves both arms"}},
      {"wave-left-hand", {"waves the left hand", "waves with the left hand", "waves the left arm"}},
      {"wave-right-hand", {"waves the right hand", "waves with the right hand", "waves the right arm"}},
      {"raise-up-both-hands", {"raises both hands", "raises both hands up", "puts both hands up"}},
      {"raise-up-left-hand", {"raises the left hand", "raises the left hand up", "puts the left hand up"}},
      {"raise-up-right-hand", {"raises the right hand", "raises the right hand up", "puts the right hand up"}},
  };
  return table;
}

const std::vector<StylePhrases>& style_phrases() {
  static const std::vector<StylePhrases> table = {
      {"normal", {"", "normally", "in an ordinary way"}, "a person"},
      {"happy", {"happily", "cheerfully", "in a happy mood"}, "a happy person"},
      {"sad", {"sadly", "gloomily", "in a sad mood"}, "a sad person"},
      {"angry", {"angrily", "furiously", "in an angry mood"}, "an angry person"},
      {"proud", {"proudly", "with pride", "in a proud manner"}, "a proud person"},
      {"not-confident", {"timidly", "without confidence", "hesitantly"}, "an unconfident person"},
      {"masculinity", {"in a masculine way", "with masculine manners", "in a manly way"}, "a masculine person"},
      {"masculine", {"in a masculine way", "with masculine manners", "in a manly way"}, "a masculine person"},
      {"feminine", {"in a feminine way", "with feminine manners", "in a ladylike way"}, "a feminine person"},
      {"childish", {"like a child", "childishly", "in a childish way"}, "a childish person"},
      {"old", {"like an old person", "like an elderly person", "in the manner of an old person"}, "an old person"},
      {"elderly",
       {"like an elderly person", "like an old person", "in the manner of an elderly person"},
       "an elderly person"},
      {"tired", {"tiredly", "wearily", "in a tired way"}, "a tired person"},
      {"exhausted", {"in an exhausted way", "wearily", "with exhaustion"}, "an exhausted person"},
      {"active", {"energetically", "actively", "in a lively way"}, "an energetic person"},
      {"youthful", {"youthfully", "in a youthful way", "like a young person"}, "a young person"},
      {"musical", {"theatrically", "like a musical performer", "in a musical style"}, "a musical performer"},
      {"giant", {"like a giant", "heavily, like a giant", "in a giant's manner"}, "a person acting like a giant"},
      {"chimpira", {"like a thug", "with a thuggish swagger", "like a street punk"}, "a thug"},
  };
  return table;
}

// The contents and styles of each dataset, as in its cfg/ label lists.
const std::array<std::vector<std::string>, 2>& dataset_contents() {
  static const std::array<std::vector<std::string>, 2> lists = {
      std::vector<std::string>{"walk", "run", "dash", "walk-back", "walk-left", "walk-right", "bow", "bye", "guide",
                               "byebye", "respond", "call", "punch", "kick", "slash", "dance-long", "dance-short"},
      std::vector<std::string>{"walk", "walk-turn-left", "walk-turn-right", "run", "wave-both-hands", "wave-left-hand",
                               "wave-right-hand", "raise-up-both-hands", "raise-up-left-hand", "raise-up-right-hand"}};
  return lists;
}

const std::array<std::vector<std::string>, 2>& dataset_styles() {
  static const std::array<std::vector<std::string>, 2> lists = {
      std::vector<std::string>{"normal", "happy", "sad", "angry", "proud", "not-confident", "masculinity", "feminine",
                               "childish", "old", "tired", "active", "musical", "giant", "chimpira"},
      std::vector<std::string>{"active", "elderly", "exhausted", "feminine", "masculine", "normal", "youthful"}};
  return lists;
}

const ContentPhrases* find_content(const std::string& label) {
  for (const auto& c : content_phrases()) {
    if (label == c.label) return &c;
  }
  return nullptr;
}

const StylePhrases* find_style(const std::string& label) {
  for (const auto& s : style_phrases()) {
    if (label == s.label) return &s;
  }
  return nullptr;
}

bool contains(const std::vector<std::string>& list, const std::string& value) {
  return std::find(list.begin(), list.end(), value) != list.end();
}

std::string join_known(const std::vector<std::string>& list) {
  std::string out;
  for (const auto& item : list) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// "dataset-1_walk" -> {1, "walk"}; nullopt when the prefix is missing.
std::optional<std::pair<int, std::string>> split_dataset_prefix(std::string_view label) {
  for (int dataset : {1, 2}) {
    const std::string prefix = "dataset-" + std::to_string(dataset) + "_";
    if (label.substr(0, prefix.size()) == prefix)
      return std::make_pair(dataset, std::string(label.substr(prefix.size())));
  }
  return std::nullopt;
}

// Non-empty lines of a label list, with their line numbers.
std::vector<std::pair<long, std::string>> read_label_list(const std::string& path) {
  const std::string text = read_file(path, kMaxTextBytes);
  std::vector<std::pair<long, std::string>> lines;
  for_each_line(strip_bom(text), [&](long number, std::string_view line) {
    const std::string_view label = trim(line);
    if (!label.empty()) lines.emplace_back(number, std::string(label));
  });
  return lines;
}

// The folder holding content_label.txt and style_label.txt for a BVH folder.
std::optional<fs::path> find_label_lists(const fs::path& bvh_dir) {
  for (const fs::path& candidate : {bvh_dir / "cfg", bvh_dir.parent_path() / "cfg"}) {
    std::error_code ec;
    if (fs::is_regular_file(candidate / "content_label.txt", ec) &&
        fs::is_regular_file(candidate / "style_label.txt", ec)) {
      return candidate;
    }
  }
  return std::nullopt;
}

long line_of_offset(std::string_view text, size_t offset) {
  offset = std::min(offset, text.size());
  return 1 + static_cast<long>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(offset), '\n'));
}

// Label from a JSON file {"content": i, "style": j}; nullopt when the JSON is
// not a Bandai label file or no label lists are found.
std::optional<BandaiLabel> label_from_json(const fs::path& json_path, const fs::path& bvh_dir) {
  const std::string json_name = json_path.string();
  const std::string text = read_file(json_name, kMaxTextBytes);
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(json_name, line_of_offset(text, e.byte == 0 ? 0 : e.byte - 1), "invalid JSON");
  }
  if (!json.is_object() || !json.contains("content") || !json.contains("style")) return std::nullopt;
  const auto lists = find_label_lists(bvh_dir);
  if (!lists) return std::nullopt;

  BandaiLabel label;
  std::string fields[2];
  const char* keys[2] = {"content", "style"};
  const char* list_names[2] = {"content_label.txt", "style_label.txt"};
  for (int k = 0; k < 2; ++k) {
    const auto& value = json.at(keys[k]);
    if (!value.is_number_integer()) {
      throw InputError(json_name, 0,
                       std::string("\"") + keys[k] + "\" must be an integer index into cfg/" + list_names[k]);
    }
    const auto index = value.get<long long>();
    const std::string list_path = (*lists / list_names[k]).string();
    const auto entries = read_label_list(list_path);
    if (index < 0 || index >= static_cast<long long>(entries.size())) {
      throw InputError(json_name, 0,
                       std::string("\"") + keys[k] + "\" is " + std::to_string(index) + ", but " + list_path + " has " +
                           std::to_string(entries.size()) + " labels");
    }
    const auto& [line, entry] = entries[static_cast<size_t>(index)];
    const auto split = split_dataset_prefix(entry);
    if (!split) throw InputError(list_path, line, "label '" + entry + "' does not start with dataset-1_ or dataset-2_");
    if (k == 1 && split->first != label.dataset) {
      throw InputError(list_path, line, "label '" + entry + "' belongs to another dataset than the content label");
    }
    label.dataset = split->first;
    fields[k] = split->second;
    const auto& known = (k == 0 ? dataset_contents() : dataset_styles())[static_cast<size_t>(label.dataset - 1)];
    if (!contains(known, fields[k])) {
      throw InputError(list_path, line,
                       std::string("unknown Bandai ") + keys[k] + " '" + fields[k] + "' (known: " + join_known(known) +
                           "); caption such files with a .txt sidecar or a CSV table");
    }
  }
  label.content = fields[0];
  label.style = fields[1];
  return label;
}

}  // namespace

// ---------------------------------------------------------------------------
// CaptionTable

CaptionTable CaptionTable::read(const std::string& csv_path) {
  CaptionTable table = parse(read_file(csv_path, kMaxTextBytes), csv_path);
  table.find_missing_below(fs::path(csv_path).parent_path());
  return table;
}

void CaptionTable::find_missing_below(const std::filesystem::path& folder) {
  const std::vector<std::string> missing = missing_files();
  if (missing.empty()) return;
  const std::string base = path_key(folder.empty() ? fs::path(".") : folder);
  // Files below the folder by their path relative to it; at most kMaxListed looked at, so a table beside a
  // huge tree costs bounded time.
  constexpr size_t kMaxListed = 200000;
  std::vector<std::string> below;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(base, fs::directory_options::follow_directory_symlink, ec);
       !ec && it != fs::recursive_directory_iterator() && below.size() < kMaxListed; it.increment(ec)) {
    if (it->is_regular_file(ec) && is_motion_file(it->path().string())) below.push_back(path_key(it->path()));
  }
  for (const std::string& key : missing) {
    const std::string relative = fs::path(key).lexically_relative(base).string();
    if (relative.empty() || relative.rfind("..", 0) == 0) continue;
    const std::string suffix = "/" + relative;
    std::vector<const std::string*> found;
    for (const std::string& path : below) {
      if (path.size() > suffix.size() && path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0) {
        found.push_back(&path);
      }
    }
    if (found.size() != 1) continue;  // none, or ambiguous: left missing (the caller warns)
    auto node = captions_.extract(key);
    std::vector<std::string>& captions = captions_[*found.front()];
    captions.insert(captions.end(), node.mapped().begin(), node.mapped().end());
  }
}

CaptionTable CaptionTable::parse(std::string_view text, const std::string& csv_path) {
  CaptionTable table;
  const fs::path base = fs::path(csv_path).parent_path();
  bool first_record = true;
  Columns columns;
  for_each_line(strip_bom(text), [&](long number, std::string_view line) {
    if (trim(line).empty()) return;
    const std::vector<std::string> fields = split_csv_line(line, csv_path, number);
    if (first_record) {
      first_record = false;
      if (const auto header = header_columns(fields)) {
        columns = *header;
        return;
      }
    }
    if (fields.size() != columns.count) {
      throw InputError(csv_path, number,
                       "expected " + std::to_string(columns.count) + " fields" +
                           (columns.count == 2 ? std::string(" (file,caption)") : std::string(" as the header")) +
                           ", found " + std::to_string(fields.size()) + "; quote a caption that contains commas");
    }
    const std::string& name = fields[columns.file];
    if (name.empty()) throw InputError(csv_path, number, "empty file name");
    const std::string caption(trim(fields[columns.caption]));
    if (caption.empty()) throw InputError(csv_path, number, "empty caption for '" + name + "'");
    fs::path file(name);
    if (file.is_relative()) file = base / file;
    table.captions_[path_key(file)].push_back(caption);
  });
  return table;
}

const std::vector<std::string>& CaptionTable::find(const std::string& bvh_path) const {
  static const std::vector<std::string> none;
  const auto it = captions_.find(path_key(bvh_path));
  return it == captions_.end() ? none : it->second;
}

std::vector<std::string> CaptionTable::missing_files() const {
  std::vector<std::string> missing;
  for (const auto& [path, captions] : captions_) {
    std::error_code ec;
    if (!fs::exists(path, ec)) missing.push_back(path);
  }
  return missing;
}

// ---------------------------------------------------------------------------
// Sidecars and the entry point

std::vector<std::string> read_caption_lines(const std::string& txt_path) {
  const std::string text = read_file(txt_path, kMaxTextBytes);
  std::vector<std::string> captions;
  for_each_line(strip_bom(text), [&](long, std::string_view line) {
    const std::string_view caption = trim(line);
    if (!caption.empty()) captions.emplace_back(caption);
  });
  if (captions.empty()) throw InputError(txt_path, 0, "no caption: the file has no non-empty line");
  return captions;
}

std::vector<std::string> captions_for(const std::string& bvh_path, const CaptionSources& sources) {
  if (sources.sidecar) {
    const fs::path sidecar = fs::path(bvh_path).replace_extension(".txt");
    std::error_code ec;
    if (fs::is_regular_file(sidecar, ec)) return read_caption_lines(sidecar.string());
  }
  for (const auto& table : sources.tables) {
    const auto& captions = table.find(bvh_path);
    if (!captions.empty()) return captions;
  }
  if (sources.bandai) {
    if (const auto label = bandai_label(bvh_path)) return bandai_captions(*label);
  }
  return {};
}

std::string take_description_for(const std::string& path, const CaptionSources& sources) {
  for (const auto& table : sources.descriptions) {
    const auto& found = table.find(path);
    if (!found.empty()) return found.front();
  }
  return "";
}

// ---------------------------------------------------------------------------
// Bandai labels

std::optional<BandaiLabel> parse_bandai_file_name(std::string_view file_name) {
  std::string stem = fs::path(std::string(file_name)).filename().string();
  if (stem.size() > 4 && lower(stem.substr(stem.size() - 4)) == ".bvh") stem.resize(stem.size() - 4);
  const auto split = split_dataset_prefix(stem);
  if (!split) return std::nullopt;
  // {content}_{style}_{take}: labels use '-' inside words, '_' between fields.
  const std::string& rest = split->second;
  const size_t first = rest.find('_');
  const size_t second = first == std::string::npos ? std::string::npos : rest.find('_', first + 1);
  if (first == std::string::npos || second == std::string::npos || first == 0 || second == first + 1) {
    return std::nullopt;
  }
  const std::string take = rest.substr(second + 1);
  if (take.empty() ||
      !std::all_of(take.begin(), take.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; })) {
    return std::nullopt;
  }
  return BandaiLabel{split->first, rest.substr(0, first), rest.substr(first + 1, second - first - 1)};
}

bool is_known_bandai_label(const BandaiLabel& label) {
  if (label.dataset != 1 && label.dataset != 2) return false;
  const size_t index = static_cast<size_t>(label.dataset - 1);
  return contains(dataset_contents()[index], label.content) && contains(dataset_styles()[index], label.style);
}

std::optional<BandaiLabel> bandai_label(const std::string& bvh_path) {
  const fs::path bvh(bvh_path);
  const fs::path json_path = fs::path(bvh).replace_extension(".json");
  std::error_code ec;
  if (fs::is_regular_file(json_path, ec)) {
    if (auto label = label_from_json(json_path, bvh.parent_path())) return label;
  }
  auto label = parse_bandai_file_name(bvh.filename().string());
  if (!label) return std::nullopt;
  if (!is_known_bandai_label(*label)) {
    const size_t index = static_cast<size_t>(label->dataset - 1);
    throw InputError(bvh_path, 0,
                     "file name looks like a Bandai label but '" + label->content + "_" + label->style +
                         "' is not in dataset-" + std::to_string(label->dataset) + " (contents: " +
                         join_known(dataset_contents()[index]) + "; styles: " + join_known(dataset_styles()[index]) +
                         "); caption such files with a .txt sidecar or a CSV table");
  }
  return label;
}

std::vector<std::string> bandai_captions(const BandaiLabel& label) {
  if (!is_known_bandai_label(label)) {
    throw std::invalid_argument("unknown Bandai label dataset-" + std::to_string(label.dataset) + "_" + label.content +
                                "_" + label.style);
  }
  const ContentPhrases& content = *find_content(label.content);
  const StylePhrases& style = *find_style(label.style);
  const auto with = [](std::string subject, const char* verb, const char* adverbial) {
    std::string caption = std::move(subject) + " " + verb;
    if (*adverbial != '\0') caption += std::string(" ") + adverbial;
    return caption;
  };
  const std::vector<std::string> candidates = {
      with("a person", content.verbs[0], style.adverbials[0]),
      with(style.subject, content.verbs[1], ""),
      with("someone", content.verbs[2], style.adverbials[1]),
      with("a person", content.verbs[1], style.adverbials[2]),
  };
  std::vector<std::string> captions;
  for (const auto& caption : candidates) {
    if (!contains(captions, caption)) captions.push_back(caption);
  }
  return captions;
}

}  // namespace nec
