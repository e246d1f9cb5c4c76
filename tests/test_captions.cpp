// Captions: sidecar text files, CSV tables, Bandai labels (synthetic files in
// a temporary folder, and the real Bandai JSON and file names when present).
#include "nec/corpus/captions.h"
#include "nec/motion/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

namespace nec {
namespace {

using testing::contains;
using testing::TempDir;

namespace fs = std::filesystem;

// The message of the InputError `f` throws, or "" when it throws none.
template <typename F>
std::string input_error(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const char* kSet1Contents =
    "dataset-1_walk\ndataset-1_run\ndataset-1_dash\ndataset-1_walk-back\ndataset-1_walk-left\n"
    "dataset-1_walk-right\ndataset-1_bow\n";
const char* kSet1Styles = "dataset-1_normal\ndataset-1_happy\ndataset-1_sad\n";

// ---------------------------------------------------------------------------
// Bandai labels

TEST(Captions, BandaiJsonIndexesTheLabelLists) {
  TempDir dir;
  dir.write("set1/cfg/content_label.txt", kSet1Contents);
  dir.write("set1/cfg/style_label.txt", kSet1Styles);
  const std::string bvh = dir.write("set1/data/dataset-1_walk-left_happy_001.bvh", "");
  dir.write("set1/data/dataset-1_walk-left_happy_001.json", "{\"content\": 4, \"style\": 1}");
  const auto captions = captions_for(bvh);
  ASSERT_GE(captions.size(), 3u);
  EXPECT_EQ(captions[0], "a person walks to the left happily");
  EXPECT_EQ(captions[1], "a happy person walks leftward");
  const auto label = bandai_label(bvh);
  ASSERT_TRUE(label);
  EXPECT_EQ(label->dataset, 1);
  EXPECT_EQ(label->content, "walk-left");
  EXPECT_EQ(label->style, "happy");
}

TEST(Captions, BandaiJsonWinsOverTheFileName) {
  TempDir dir;
  dir.write("cfg/content_label.txt", kSet1Contents);  // cfg/ may also sit next to the BVH
  dir.write("cfg/style_label.txt", kSet1Styles);
  const std::string bvh = dir.write("dataset-1_walk_normal_001.bvh", "");
  dir.write("dataset-1_walk_normal_001.json", "{\"content\": 6, \"style\": 2}");
  const auto label = bandai_label(bvh);
  ASSERT_TRUE(label);
  EXPECT_EQ(label->content, "bow");
  EXPECT_EQ(label->style, "sad");
  EXPECT_EQ(captions_for(bvh)[0], "a person bows sadly");
}

TEST(Captions, BandaiFileNameAloneGivesTheLabel) {
  TempDir dir;
  const std::string bvh = dir.write("takes/dataset-2_raise-up-left-hand_elderly_003.bvh", "");
  const auto captions = captions_for(bvh);
  ASSERT_FALSE(captions.empty());
  EXPECT_EQ(captions[0], "a person raises the left hand like an elderly person");
  const auto parsed = parse_bandai_file_name("dataset-1_not-confident_walk-back_002.bvh");
  ASSERT_TRUE(parsed);  // fields are split at '_', words keep their '-'
  EXPECT_EQ(parsed->content, "not-confident");
  EXPECT_EQ(parsed->style, "walk-back");
  EXPECT_FALSE(is_known_bandai_label(*parsed));
  EXPECT_FALSE(parse_bandai_file_name("walk_happy_001.bvh"));
  EXPECT_FALSE(parse_bandai_file_name("dataset-3_walk_happy_001.bvh"));
  EXPECT_FALSE(parse_bandai_file_name("dataset-1_walk_happy.bvh"));
  EXPECT_FALSE(parse_bandai_file_name("dataset-1_walk_happy_take.bvh"));
  // Set 2's vocabulary is not set 1's.
  EXPECT_TRUE(is_known_bandai_label({2, "wave-left-hand", "youthful"}));
  EXPECT_FALSE(is_known_bandai_label({1, "wave-left-hand", "youthful"}));
  EXPECT_FALSE(is_known_bandai_label({3, "walk", "normal"}));
}

TEST(Captions, UnknownBandaiLabelsAreInputErrors) {
  TempDir dir;
  const std::string by_name = dir.write("dataset-1_fly_happy_001.bvh", "");
  const std::string message = input_error([&] { captions_for(by_name); });
  EXPECT_TRUE(contains(message, by_name)) << message;
  EXPECT_TRUE(contains(message, "'fly_happy'")) << message;
  EXPECT_TRUE(contains(message, "sidecar")) << message;

  // An unknown label in a list: the error names the list and its line.
  dir.write("set/cfg/content_label.txt", "dataset-1_walk\n\ndataset-1_fly\n");
  dir.write("set/cfg/style_label.txt", kSet1Styles);
  const std::string bvh = dir.write("set/data/take.bvh", "");
  dir.write("set/data/take.json", "{\"content\": 1, \"style\": 0}");
  const std::string list_error = input_error([&] { captions_for(bvh); });
  EXPECT_TRUE(contains(list_error, (dir / "set/cfg/content_label.txt") + ":3: unknown Bandai content 'fly'"))
      << list_error;

  EXPECT_THROW(bandai_captions({1, "fly", "happy"}), std::invalid_argument);
}

TEST(Captions, BadBandaiJsonIsAnInputError) {
  TempDir dir;
  dir.write("cfg/content_label.txt", kSet1Contents);
  dir.write("cfg/style_label.txt", kSet1Styles);
  const std::string bvh = dir.write("take.bvh", "");
  const std::string json = dir / "take.json";

  dir.write("take.json", "{\"content\": 7, \"style\": 0}");  // 7 contents: indices 0..6
  std::string message = input_error([&] { captions_for(bvh); });
  EXPECT_TRUE(contains(message, json + ": \"content\" is 7")) << message;

  dir.write("take.json", "{\"content\": 0, \"style\": -1}");
  message = input_error([&] { captions_for(bvh); });
  EXPECT_TRUE(contains(message, "\"style\" is -1")) << message;

  dir.write("take.json", "{\"content\": \"walk\", \"style\": 0}");
  message = input_error([&] { captions_for(bvh); });
  EXPECT_TRUE(contains(message, "\"content\" must be an integer")) << message;

  dir.write("take.json", "{\n  \"content\": 1,\n  \"style\" 0\n}");
  message = input_error([&] { captions_for(bvh); });
  EXPECT_TRUE(contains(message, json + ":3: invalid JSON")) << message;

  // A JSON that is not a label file is not an error: no label, no captions.
  dir.write("take.json", "{\"fps\": 30}");
  EXPECT_TRUE(captions_for(bvh).empty());
}

TEST(Captions, EveryBandaiLabelHasSeveralCleanPhrasings) {
  const std::vector<std::vector<std::string>> contents = {
      {"walk", "run", "dash", "walk-back", "walk-left", "walk-right", "bow", "bye", "guide", "byebye", "respond",
       "call", "punch", "kick", "slash", "dance-long", "dance-short"},
      {"walk", "walk-turn-left", "walk-turn-right", "run", "wave-both-hands", "wave-left-hand", "wave-right-hand",
       "raise-up-both-hands", "raise-up-left-hand", "raise-up-right-hand"}};
  const std::vector<std::vector<std::string>> styles = {
      {"normal", "happy", "sad", "angry", "proud", "not-confident", "masculinity", "feminine", "childish", "old",
       "tired", "active", "musical", "giant", "chimpira"},
      {"active", "elderly", "exhausted", "feminine", "masculine", "normal", "youthful"}};
  int count = 0;
  for (int set = 0; set < 2; ++set) {
    for (const auto& content : contents[set]) {
      for (const auto& style : styles[set]) {
        const BandaiLabel label{set + 1, content, style};
        ASSERT_TRUE(is_known_bandai_label(label)) << content << " " << style;
        const auto captions = bandai_captions(label);
        EXPECT_EQ(captions, bandai_captions(label));  // deterministic
        ASSERT_GE(captions.size(), 3u) << content << " " << style;
        EXPECT_EQ(captions[0].rfind("a person ", 0), 0u) << captions[0];
        for (size_t i = 0; i < captions.size(); ++i) {
          const std::string& c = captions[i];
          EXPECT_FALSE(contains(c, "  ") || c.back() == ' ' || contains(c, "_")) << "'" << c << "'";
          for (size_t k = 0; k < i; ++k) EXPECT_NE(c, captions[k]);
          // Sides and directions survive every phrasing.
          const bool left = contains(content, "left");
          const bool right = contains(content, "right");
          if (left != right) {
            EXPECT_TRUE(contains(c, left ? "left" : "right")) << c;
            EXPECT_FALSE(contains(c, left ? "right" : "left")) << c;
          }
          if (content == "walk-back") {
            EXPECT_TRUE(contains(c, "backward")) << c;
          }
          if (contains(content, "both")) {
            EXPECT_TRUE(contains(c, "both")) << c;
          }
        }
        ++count;
      }
    }
  }
  EXPECT_EQ(count, 17 * 15 + 10 * 7);
  EXPECT_EQ(bandai_captions({1, "walk", "normal"})[0], "a person walks forward");
  EXPECT_EQ(bandai_captions({2, "walk-turn-right", "exhausted"})[0],
            "a person walks and turns right in an exhausted way");
}

// The real Bandai files: every JSON gives the same label as its file name,
// and captions_for finds captions for every take.
TEST(Captions, RealBandaiLabelsAgreeWithFileNames) {
  const std::string data = testing::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "no shared data";
  int checked = 0;
  for (const char* set : {"bandai/set1/data", "bandai/set2/data"}) {
    const fs::path dir = fs::path(data) / set;
    if (!fs::is_directory(dir)) {  // the shared data is there: so must its Bandai sets be (the count below fails)
      ADD_FAILURE() << dir << " missing from the shared data";
      continue;
    }
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().extension() != ".json") continue;
      const std::string bvh = fs::path(entry.path()).replace_extension(".bvh").string();
      const auto from_json = bandai_label(bvh);
      const auto from_name = parse_bandai_file_name(bvh);
      ASSERT_TRUE(from_json) << bvh;
      ASSERT_TRUE(from_name) << bvh;
      EXPECT_EQ(from_json->dataset, from_name->dataset) << bvh;
      EXPECT_EQ(from_json->content, from_name->content) << bvh;
      EXPECT_EQ(from_json->style, from_name->style) << bvh;
      const auto captions = captions_for(bvh);
      ASSERT_GE(captions.size(), 3u) << bvh;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 175 + 420);
  const fs::path walk_left = fs::path(data) / "bandai/set1/data/dataset-1_walk-left_happy_001.bvh";
  if (fs::exists(walk_left)) {
    EXPECT_EQ(captions_for(walk_left.string())[0], "a person walks to the left happily");
  }
}

// ---------------------------------------------------------------------------
// Sidecars

TEST(Captions, SidecarHasOneCaptionPerNonEmptyLine) {
  TempDir dir;
  const std::string bvh = dir.write("clip.bvh", "");
  dir.write("clip.txt", "\xEF\xBB\xBF  a dog sniffs the ground\r\n\r\n\ta dog looks for something  \r\n   \n");
  const auto captions = captions_for(bvh);
  ASSERT_EQ(captions.size(), 2u);
  EXPECT_EQ(captions[0], "a dog sniffs the ground");
  EXPECT_EQ(captions[1], "a dog looks for something");

  CaptionSources no_sidecar;
  no_sidecar.sidecar = false;
  EXPECT_TRUE(captions_for(bvh, no_sidecar).empty());
}

TEST(Captions, EmptySidecarIsAnInputError) {
  TempDir dir;
  const std::string bvh = dir.write("clip.bvh", "");
  const std::string txt = dir.write("clip.txt", " \n\r\n\t\n");
  const std::string message = input_error([&] { captions_for(bvh); });
  EXPECT_TRUE(contains(message, txt + ": no caption")) << message;
  EXPECT_TRUE(contains(input_error([&] { read_caption_lines(dir / "absent.txt"); }), "absent.txt: cannot open"));
}

TEST(Captions, SourcesAreTriedInOrder) {
  TempDir dir;
  const std::string bvh = dir.write("dataset-1_bow_sad_001.bvh", "");
  const std::string csv = dir.write("captions.csv", "dataset-1_bow_sad_001.bvh,from the table\n");
  CaptionSources sources;
  sources.tables.push_back(CaptionTable::read(csv));
  // Bandai file name only.
  CaptionSources bandai_only;
  EXPECT_EQ(captions_for(bvh, bandai_only)[0], "a person bows sadly");
  // The table wins over the file name.
  EXPECT_EQ(captions_for(bvh, sources), std::vector<std::string>{"from the table"});
  // The sidecar wins over both.
  dir.write("dataset-1_bow_sad_001.txt", "from the sidecar\n");
  EXPECT_EQ(captions_for(bvh, sources), std::vector<std::string>{"from the sidecar"});
  // Nothing applies: no captions.
  const std::string plain = dir.write("walk01.bvh", "");
  EXPECT_TRUE(captions_for(plain, sources).empty());
  CaptionSources none;
  none.sidecar = false;
  none.bandai = false;
  EXPECT_TRUE(captions_for(bvh, none).empty());
}

// ---------------------------------------------------------------------------
// CSV tables

TEST(Captions, CsvTableParsesQuotesHeadersAndRelativePaths) {
  TempDir dir;
  const std::string walk = dir.write("corpus/dogs/walk.bvh", "");
  const std::string sit = dir.write("corpus/dogs/sit.bvh", "");
  const std::string text =
      "\xEF\xBB\xBF"
      "File,Caption\r\n"
      "dogs/walk.bvh,a dog walks\r\n"
      "\r\n"
      "\"dogs/walk.bvh\", \"a dog walks, then stops\"\n"
      "dogs/../dogs/sit.bvh,\"a dog sits, says \"\"woof\"\"\"\n"
      "  dogs/sit.bvh  ,  a dog sits down  \n"
      "/elsewhere/absolute.bvh,far away";
  const std::string csv = dir.write("corpus/captions.csv", text);
  const CaptionTable table = CaptionTable::read(csv);
  EXPECT_EQ(table.file_count(), 3u);
  EXPECT_EQ(table.find(walk), (std::vector<std::string>{"a dog walks", "a dog walks, then stops"}));
  EXPECT_EQ(table.find(sit), (std::vector<std::string>{"a dog sits, says \"woof\"", "a dog sits down"}));
  EXPECT_EQ(table.find("/elsewhere/absolute.bvh"), std::vector<std::string>{"far away"});
  EXPECT_EQ(table.find("/elsewhere/../elsewhere/absolute.bvh"), std::vector<std::string>{"far away"});
  EXPECT_TRUE(table.find(dir / "corpus/run.bvh").empty());
  // Paths are relative to the CSV's folder, not to the working directory.
  const fs::path before = fs::current_path();
  fs::current_path(dir / "corpus/dogs");
  EXPECT_EQ(table.find("walk.bvh").size(), 2u);
  fs::current_path(before);
  // Files the table names that do not exist.
  EXPECT_EQ(table.missing_files(), std::vector<std::string>{"/elsewhere/absolute.bvh"});

  // Without a header the first row is data.
  const CaptionTable plain = CaptionTable::parse("a.bvh,first\nb.bvh,second\n", (dir / "t.csv"));
  EXPECT_EQ(plain.file_count(), 2u);
  EXPECT_EQ(plain.find(dir / "a.bvh"), std::vector<std::string>{"first"});
}

TEST(Captions, CsvTableWithMoreColumnsTakesTheNamedOnesAndFindsFilesBelowItsFolder) {
  TempDir dir;
  const std::string walk = dir.write("cmu/bvh/02_01.bvh", "");
  dir.write("cmu/bvh/a/05_01.bvh", "");
  dir.write("cmu/bvh/b/05_01.bvh", "");
  const std::string csv = dir.write("cmu/descriptions.csv",
                                    "file,description,subject\n"
                                    "02_01.bvh,walk,\"Subject #2 (various, expressions)\"\n"
                                    "05_01.bvh,dance,Subject #5\n"
                                    "99_01.bvh,run,Subject #99\n");
  const CaptionTable table = CaptionTable::read(csv);
  // 02_01.bvh is not beside the CSV but in bvh/ below it; 05_01.bvh is below it twice, so it stays unresolved.
  EXPECT_EQ(table.find(walk), std::vector<std::string>{"walk"});
  EXPECT_TRUE(table.find(dir / "cmu/bvh/a/05_01.bvh").empty());
  EXPECT_EQ(table.missing_files().size(), 2u);
  // Columns in another order.
  const CaptionTable swapped = CaptionTable::parse("text,subject,path\na dog sits,5,x.bvh\n", dir / "t.csv");
  EXPECT_EQ(swapped.find(dir / "x.bvh"), std::vector<std::string>{"a dog sits"});
  EXPECT_EQ(input_error([&] { CaptionTable::parse("file,description,subject\nx.bvh,walk\n", "/d/t.csv"); }),
            "/d/t.csv:2: expected 3 fields as the header, found 2; quote a caption that contains commas");
}

TEST(Captions, CsvErrorsNameTheFileAndLine) {
  const std::string csv = "/data/captions.csv";
  const auto error = [&](const std::string& text) { return input_error([&] { CaptionTable::parse(text, csv); }); };
  EXPECT_EQ(error("file,caption\nwalk.bvh,a dog walks\nsit.bvh,\n"), csv + ":3: empty caption for 'sit.bvh'");
  EXPECT_EQ(error("walk.bvh,\"   \"\n"), csv + ":1: empty caption for 'walk.bvh'");
  EXPECT_EQ(error("walk.bvh,a dog\n,a cat\n"), csv + ":2: empty file name");
  EXPECT_TRUE(
      contains(error("walk.bvh,a dog walks, then sits\n"), csv + ":1: expected 2 fields (file,caption), found 3"));
  EXPECT_TRUE(contains(error("walk.bvh\n"), csv + ":1: expected 2 fields"));
  EXPECT_EQ(error("a.bvh,ok\nwalk.bvh,\"a dog walks\n"), csv + ":2: unterminated quoted field");
  EXPECT_TRUE(contains(error("walk.bvh,\"a dog\" walks\n"), csv + ":1: unexpected text after a closing quote"));
  EXPECT_TRUE(contains(error("walk.bvh,a 12\" dog\n"), csv + ":1: a quote inside an unquoted field"));
  EXPECT_TRUE(contains(input_error([] { CaptionTable::read("/nonexistent/captions.csv"); }),
                       "/nonexistent/captions.csv: cannot open"));
}

}  // namespace
}  // namespace nec
