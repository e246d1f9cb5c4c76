// train/config_fields.h: one field list reads, writes, rejects, diffs and describes a config.
#include "nec/train/config_fields.h"

#include "nec/motion/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

namespace {

using nec::train::OnResume;
using nlohmann::json;

enum class Shape { Round, Square };
std::string shape_name(Shape shape) { return shape == Shape::Round ? "round" : "square"; }

struct Inner {
  double rate = 0.5;
  std::vector<std::string> names{"a"};
};

struct Outer {
  int64_t steps = 10;
  bool on = true;
  uint64_t seed = 1;
  int small = 3;
  Shape shape = Shape::Round;
  std::string label = "x";
  Inner inner;
};

void visit_fields(nec::train::ConfigVisitor& v, Inner& c) {
  v.field("rate", c.rate, "a rate", OnResume::kMayChange);
  v.field("names", c.names, "some names");
}

void visit_fields(nec::train::ConfigVisitor& v, Outer& c) {
  v.field("steps", c.steps, "the last step", OnResume::kMayChange);
  v.field("on", c.on, "a switch");
  v.field("seed", c.seed, "a seed");
  v.field("small", c.small, "a small int");
  v.choice("shape", c.shape, {Shape::Round, Shape::Square}, shape_name, "a shape");
  v.field("label", c.label, "a label");
  v.object("inner", c.inner, "the inner part");
}

Outer read(const std::string& text, bool required = false) {
  return nec::train::read_config<Outer>(json::parse(text), {"cfg.json", "see the docs", "", required});
}

std::string error_of(const std::string& text, bool required = false) {
  try {
    read(text, required);
  } catch (const nec::InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ConfigFields, MissingFieldsKeepTheirDefaultsAndGivenOnesAreRead) {
  const Outer defaults = read("{}");
  EXPECT_EQ(defaults.steps, 10);
  EXPECT_EQ(defaults.inner.names, std::vector<std::string>{"a"});
  const Outer c = read(R"({"steps": 7, "on": false, "seed": 18446744073709551615, "small": -2, "shape": "square",
                           "label": "y", "inner": {"rate": 2, "names": ["p", "q"]}})");
  EXPECT_EQ(c.steps, 7);
  EXPECT_FALSE(c.on);
  EXPECT_EQ(c.seed, 18446744073709551615ull);
  EXPECT_EQ(c.small, -2);
  EXPECT_EQ(c.shape, Shape::Square);
  EXPECT_EQ(c.label, "y");
  EXPECT_DOUBLE_EQ(c.inner.rate, 2.0);
  EXPECT_EQ(c.inner.names, (std::vector<std::string>{"p", "q"}));
}

TEST(ConfigFields, WritesEveryFieldAndReadsItBack) {
  Outer c;
  c.steps = 99;
  c.shape = Shape::Square;
  c.inner.rate = 0.25;
  const json written = nec::train::write_config(c);
  EXPECT_EQ(written, json::parse(R"({"steps": 99, "on": true, "seed": 1, "small": 3, "shape": "square", "label": "x",
                                     "inner": {"rate": 0.25, "names": ["a"]}})"));
  EXPECT_EQ(nec::train::write_config(read(written.dump(), /*required=*/true)), written);
}

TEST(ConfigFields, UnknownFieldsAreRejectedAtEveryLevelButACommentIsAllowed) {
  EXPECT_EQ(read(R"({"comment": "a note", "inner": {"comment": "another"}})").steps, 10);
  EXPECT_EQ(error_of(R"({"stpes": 3})"),
            "cfg.json: field 'stpes' is not a known field (known here: steps, on, seed, small, shape, label, inner); "
            "see the docs");
  EXPECT_NE(error_of(R"({"inner": {"rat": 3}})").find("field 'inner.rat' is not a known field (known here: rate, names)"),
            std::string::npos);
}

TEST(ConfigFields, WrongTypesAndRangesNameTheField) {
  EXPECT_NE(error_of(R"({"steps": 2.5})").find("field 'steps' must be an integer"), std::string::npos);
  EXPECT_NE(error_of(R"({"steps": "3"})").find("field 'steps' must be an integer"), std::string::npos);
  EXPECT_NE(error_of(R"({"on": 1})").find("field 'on' must be true or false"), std::string::npos);
  EXPECT_NE(error_of(R"({"seed": -1})").find("field 'seed' must be a non-negative integer"), std::string::npos);
  EXPECT_NE(error_of(R"({"small": 10000000000})").find("field 'small' is out of range"), std::string::npos);
  EXPECT_NE(error_of(R"({"steps": 18446744073709551615})").find("field 'steps' is out of range"), std::string::npos);
  EXPECT_NE(error_of(R"({"inner": 3})").find("field 'inner' must be an object"), std::string::npos);
  EXPECT_NE(error_of(R"({"inner": {"names": [1]}})").find("field 'inner.names' must be a list of strings"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"inner": {"rate": "fast"}})").find("field 'inner.rate' must be a number"), std::string::npos);
  EXPECT_NE(error_of(R"({"shape": "hex"})").find("field 'shape' is 'hex', not one of: round, square"),
            std::string::npos);
  EXPECT_NE(error_of("[1, 2]").find("cfg.json: a config must be a JSON object"), std::string::npos);
}

TEST(ConfigFields, ARequiredReadNamesTheMissingFieldWithItsPrefix) {
  const json file = json::parse(R"({"model": {"steps": 1}})");
  try {
    nec::train::read_config_object<Outer>(file, "model", {"ckpt/config.json", "", "", true});
    FAIL() << "a missing field was accepted";
  } catch (const nec::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("field 'model.on' is missing"), std::string::npos) << e.what();
  }
  try {
    nec::train::read_config_object<Outer>(file, "tokenizer", {"ckpt/config.json", "", "", true});
    FAIL() << "a missing object was accepted";
  } catch (const nec::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("field 'tokenizer' must be a JSON object"), std::string::npos) << e.what();
  }
}

struct Grown {
  int64_t width = 4;
  bool new_switch = false;  // added later: old checkpoints lack it and did what false does
};

void visit_fields(nec::train::ConfigVisitor& v, Grown& c) {
  v.field("width", c.width, "a width");
  v.added_field("new_switch", c.new_switch, "a switch added later");
}

TEST(ConfigFields, ACheckpointMayLackAnAddedFieldButNotAnOtherOne) {
  const nec::train::ReadOptions checkpoint{"ckpt/config.json", "", "", true};
  const Grown old_one = nec::train::read_config<Grown>(json::parse(R"({"width": 8})"), checkpoint);
  EXPECT_EQ(old_one.width, 8);
  EXPECT_FALSE(old_one.new_switch);
  const Grown new_one = nec::train::read_config<Grown>(json::parse(R"({"width": 8, "new_switch": true})"), checkpoint);
  EXPECT_TRUE(new_one.new_switch);
  EXPECT_EQ(nec::train::write_config(new_one), json::parse(R"({"width": 8, "new_switch": true})"));
  EXPECT_THROW(nec::train::read_config<Grown>(json::parse(R"({"new_switch": true})"), checkpoint), nec::InputError);
}

TEST(ConfigFields, TheFieldsThatMayChangeOnResumeAreTheMarkedOnesByDottedName) {
  EXPECT_EQ(nec::train::fields_that_may_change<Outer>(), (std::set<std::string>{"steps", "inner.rate"}));
}

TEST(ConfigFields, TheHelpListsEveryFieldWithItsValueAndHelp) {
  Outer c;
  c.inner.rate = 0.75;
  const std::string help = nec::train::describe_config(c);
  for (const char* line : {"  steps = 10", "  shape = \"round\"", "  inner.", "  inner.rate = 0.75",
                           "  inner.names = [\"a\"]"}) {
    EXPECT_NE(help.find(line), std::string::npos) << line << "\n" << help;
  }
  EXPECT_NE(help.find("a shape (round, square)"), std::string::npos) << help;
  EXPECT_NE(help.find("the last step; may change on --resume"), std::string::npos) << help;
  EXPECT_EQ(std::count(help.begin(), help.end(), '\n'), 9);  // 8 fields and one object
}

}  // namespace
