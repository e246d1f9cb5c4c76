// Captions for BVH files: from the user's own text files, or made from the
// labels of the Bandai Namco motion datasets.
//
//   CaptionSources sources;
//   sources.tables.push_back(CaptionTable::read("captions.csv"));   // optional
//   std::vector<std::string> captions = captions_for("data/walk_01.bvh", sources);
//   // {} when no source applies
//
// Sources, tried in this order; the first that applies gives all captions:
//   1. sidecar: `clip.txt` next to `clip.bvh`, one caption per non-empty line;
//   2. tables: all rows naming this file in the first CSV table (in the
//      order given) that names it;
//   3. Bandai labels: `clip.json` next to the BVH ({"content": 6, "style": 11},
//      0-based indices into `cfg/content_label.txt` and `cfg/style_label.txt`
//      found in the BVH's folder or its parent), else the file name
//      `dataset-1_{content}_{style}_{take}.bvh` / `dataset-2_...`. A JSON
//      without both keys, or without label lists to index, is not a label.
// Bandai labels are turned into several deterministic natural phrasings:
//   walk-left + happy -> "a person walks to the left happily", "a happy person walks leftward", ...
// A Bandai label outside the two datasets' vocabularies is an InputError that
// names the file (a generic caption would teach the model a wrong sentence);
// give such files a sidecar or a table row instead.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace nec {

// A CSV table of captions: `file,caption` per row. The header row
// (`file,caption`, also `path`/`filename` and `text`/`description`) is
// optional; fields may be quoted ("a dog walks, then sits", "" for a quote);
// several rows may name the same file; relative paths are relative to the
// CSV's folder; read() also finds a relative path that names no file there in
// the folders below it (CMU's descriptions.csv names takes kept in bvh/), when
// exactly one file matches. A header row may name more columns (`file,
// description,subject`): the file and caption columns are taken, the rest
// ignored. Blank lines are skipped; an empty caption, an empty file name, a row
// whose field count differs from the header's (two without a header) or an
// unterminated quote is an InputError naming the CSV and the line.
class CaptionTable {
 public:
  static CaptionTable read(const std::string& csv_path);
  // `csv_path` names the table in errors and anchors relative paths.
  static CaptionTable parse(std::string_view text, const std::string& csv_path);

  // Captions of a BVH file in row order; empty when the table does not name it.
  const std::vector<std::string>& find(const std::string& bvh_path) const;
  // Number of distinct files the table names.
  size_t file_count() const { return captions_.size(); }
  // Files the table names that do not exist (for a warning per file).
  std::vector<std::string> missing_files() const;

 private:
  void find_missing_below(const std::filesystem::path& folder);

  std::map<std::string, std::vector<std::string>> captions_;  // normalized path -> captions
};

struct CaptionSources {
  bool sidecar = true;               // read `clip.txt` next to `clip.bvh`
  std::vector<CaptionTable> tables;  // CSV tables, tried in order
  bool bandai = true;                // Bandai JSON labels or file-name pattern
  // Tables of take descriptions (`file,description`): a described take without captions is still cut by the
  // segmenter, and each clip gets the description's parts that agree with it (corpus/take_description.h).
  std::vector<CaptionTable> descriptions;
};

// Captions of one BVH file from the first source that applies; {} if none.
// Throws InputError for a malformed sidecar, Bandai JSON or label list.
std::vector<std::string> captions_for(const std::string& bvh_path, const CaptionSources& sources = {});

// The description of a take from the first description table that names it; "" when none does.
std::string take_description_for(const std::string& path, const CaptionSources& sources);

// Captions from a sidecar text file: one per non-empty line (trimmed, CRLF
// and a UTF-8 byte order mark tolerated). A file without any caption is an
// InputError.
std::vector<std::string> read_caption_lines(const std::string& txt_path);

// A Bandai Namco label: dataset 1 or 2, content and style as in the label
// lists without the `dataset-N_` prefix, e.g. {1, "walk-left", "happy"}.
struct BandaiLabel {
  int dataset = 1;      // 1 or 2
  std::string content;  // e.g. "walk-left"
  std::string style;    // e.g. "happy"
};

// The label of a BVH file from its JSON and label lists, else from its file
// name; nullopt when neither applies. Throws InputError naming the JSON, the
// label list (with the line) or the BVH for bad indices or unknown labels.
std::optional<BandaiLabel> bandai_label(const std::string& bvh_path);
// The label encoded in a file name such as `dataset-2_wave-left-hand_elderly_003.bvh`
// (directories are ignored); nullopt when the name does not follow the pattern.
// Does not check that content and style are known.
std::optional<BandaiLabel> parse_bandai_file_name(std::string_view file_name);
// Whether the datasets' vocabularies contain the content and style of `label`.
bool is_known_bandai_label(const BandaiLabel& label);
// Natural phrasings, canonical one first, deterministic and without
// duplicates. Throws std::invalid_argument for a label that is not known.
std::vector<std::string> bandai_captions(const BandaiLabel& label);

}  // namespace nec
