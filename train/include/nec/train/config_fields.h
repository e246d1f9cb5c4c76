// Config structs declare their fields once, in one visit_fields function; that
// one list reads and writes JSON, rejects unknown fields (a "comment" is
// allowed in every object), names the fields a resumed run may change, and
// writes the --help text.
//
//   void visit_fields(train::ConfigVisitor& v, LossWeights& c) {
//     v.field("rotation", c.rotation, "weight of the rotation term");
//     v.field("steps", c.steps, "the step training ends at", train::OnResume::kMayChange);
//     v.object("quantizer", c.quantizer, "the residual quantizer");
//     v.choice("kind", c.kind, {Kind::A, Kind::B}, to_string, "which model");
//   }
//   TatTrainConfig c = read_config<TatTrainConfig>(root, {"configs/tat_cpu.json"});
//   OwoConfig e = read_config_object<OwoConfig>(checkpoint, "encoder", {path, hint, "", true});
//   nlohmann::json j = write_config(c);
//   std::set<std::string> may_change = fields_that_may_change<TatTrainConfig>();  // {"steps", ...}
//   std::string help = describe_config(TatTrainConfig{});                         // one line per field
//
// Nested objects are found by argument-dependent lookup: a struct's
// visit_fields lives in its own namespace (or in nec::train).
#pragma once

#include "nec/motion/error.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <set>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace nec::train {

// Whether a field may differ between a checkpoint's config and the run that resumes it.
enum class OnResume { kFixed, kMayChange };

// Whether a checkpoint must hold a field, or may lack it because it was written before the field existed.
enum class InCheckpoints { kRequired, kMayLack };

struct FieldInfo {
  const char* name;                               // the JSON key, e.g. "learning_rate"
  const char* help;                               // one line for --help
  OnResume on_resume = OnResume::kFixed;
  const std::vector<std::string>* choices = nullptr;  // a string field restricted to these
  InCheckpoints in_checkpoints = InCheckpoints::kRequired;
};

using FieldValue =
    std::variant<bool*, int*, int64_t*, uint64_t*, double*, std::string*, std::vector<std::string>*>;

class ConfigVisitor {
 public:
  virtual ~ConfigVisitor() = default;

  template <typename T>
  void field(const char* name, T& value, const char* help, OnResume on_resume = OnResume::kFixed) {
    visit(FieldInfo{name, help, on_resume, nullptr}, FieldValue(&value));
  }

  // A field added after checkpoints were written: one that lacks it reads the default in `value`, which
  // must keep what those checkpoints did.
  template <typename T>
  void added_field(const char* name, T& value, const char* help) {
    visit(FieldInfo{name, help, OnResume::kFixed, nullptr, InCheckpoints::kMayLack}, FieldValue(&value));
  }

  // An enum stored by name: `names_of(value)` gives the name of each of `options`.
  template <typename Enum, typename NameOf>
  void choice(const char* name, Enum& value, const std::vector<Enum>& options, NameOf names_of, const char* help) {
    std::vector<std::string> names;
    for (const Enum option : options) names.push_back(names_of(option));
    std::string text = names_of(value);
    visit(FieldInfo{name, help, OnResume::kFixed, &names}, FieldValue(&text));
    for (size_t i = 0; i < options.size(); ++i) {
      if (names[i] == text) value = options[i];
    }
  }

  // A nested object, whose fields its own visit_fields declares.
  template <typename T>
  void object(const char* name, T& value, const char* help) {
    enter(name, help);
    visit_fields(*this, value);
    leave();
  }

 protected:
  virtual void visit(const FieldInfo& info, FieldValue value) = 0;
  virtual void enter(const char* name, const char* help) = 0;
  virtual void leave() = 0;
};

struct ReadOptions {
  std::string file;     // named in every error, e.g. "configs/tat_cpu.json"
  std::string hint;     // appended to errors, e.g. "see configs/tat_cpu.json for every field"
  std::string prefix;   // dotted path of the object being read, e.g. "tokenizer." in a checkpoint
  bool required = false;  // false: a missing field keeps its default (config files); true: it is an error
                          // (checkpoints), but for fields declared with added_field
};

// Reads an object into a struct's fields, checking each value's type and
// range, and rejecting keys no field declares. Errors are
// InputError(file, 0, "field 'a.b' ...").
class JsonConfigReader final : public ConfigVisitor {
 public:
  JsonConfigReader(const nlohmann::json& root, ReadOptions options);
  // Rejects the keys of the top object that no field declared; call after visiting.
  void finish();

 protected:
  void visit(const FieldInfo& info, FieldValue value) override;
  void enter(const char* name, const char* help) override;
  void leave() override;

 private:
  struct Level {
    const nlohmann::json* object;
    std::string prefix;
    std::vector<std::string> declared;
  };
  [[noreturn]] void fail(const std::string& name, const std::string& problem) const;
  void check_declared(const Level& level) const;
  ReadOptions options_;
  std::vector<Level> levels_;
};

class JsonConfigWriter final : public ConfigVisitor {
 public:
  const nlohmann::json& result() const { return levels_.front(); }

 protected:
  void visit(const FieldInfo& info, FieldValue value) override;
  void enter(const char* name, const char* help) override;
  void leave() override;

 private:
  std::vector<nlohmann::json> levels_{nlohmann::json::object()};
  std::vector<std::string> names_;
};

// A visitor that knows the dotted prefix of the object it is in, e.g. "data.augment.".
class DottedVisitor : public ConfigVisitor {
 protected:
  void enter(const char* name, const char* help) override;
  void leave() override;
  const std::string& prefix() const { return prefix_; }

 private:
  std::string prefix_;
  std::vector<size_t> lengths_;
};

// Dotted names of the fields marked OnResume::kMayChange.
class MayChangeCollector final : public DottedVisitor {
 public:
  const std::set<std::string>& result() const { return names_; }

 protected:
  void visit(const FieldInfo& info, FieldValue value) override;

 private:
  std::set<std::string> names_;
};

// One line per field: dotted name, its value in the visited config, help.
class HelpWriter final : public DottedVisitor {
 public:
  std::string result() const;

 protected:
  void visit(const FieldInfo& info, FieldValue value) override;
  void enter(const char* name, const char* help) override;

 private:
  std::vector<std::pair<std::string, std::string>> lines_;  // "name = value", help
};

// The cadence every training config has, one list for all of them: "steps",
// "log_every", "validate_every", "checkpoint_every" (0: only at the end;
// validation: never), each one a resumed run may change.
void visit_cadence_fields(ConfigVisitor& v, int64_t& steps, int64_t& log_every, int64_t& validate_every,
                          int64_t& checkpoint_every);
// What every config's validate() says when a cadence field is negative.
inline constexpr const char* kCadenceRule =
    "log_every, validate_every and checkpoint_every must be >= 0 (0: only at the end; validation: never)";
inline bool valid_cadence(int64_t log_every, int64_t validate_every, int64_t checkpoint_every) {
  return log_every >= 0 && validate_every >= 0 && checkpoint_every >= 0;
}

// The JSON of a config file; InputError naming the file when it cannot be read or is not valid JSON.
nlohmann::json read_config_json(const std::string& path);

// Reads `root` into a default-constructed Config (validation is the caller's).
template <typename Config>
Config read_config(const nlohmann::json& root, ReadOptions options) {
  Config config;
  JsonConfigReader reader(root, std::move(options));
  visit_fields(reader, config);
  reader.finish();
  return config;
}

// read_config, then config.validate(): its std::invalid_argument becomes an
// InputError naming the file (a config file's whole check).
template <typename Config>
Config read_valid_config(const nlohmann::json& root, ReadOptions options) {
  const std::string file = options.file;
  Config config = read_config<Config>(root, std::move(options));
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(file, 0, e.what());
  }
  return config;
}

// The object `parent[key]`, a part of a bigger file (e.g. a checkpoint's
// "tokenizer"), read with the prefix "key."; an absent key is an error.
template <typename Config>
Config read_config_object(const nlohmann::json& parent, const std::string& key, ReadOptions options) {
  static const nlohmann::json kAbsent;
  const auto it = parent.find(key);
  options.prefix += key + ".";
  return read_config<Config>(it == parent.end() ? kAbsent : *it, std::move(options));
}

// A training config file's whole check: read_config_json, then read_valid_config with `hint` ending each error.
template <typename Config>
Config read_config_file(const std::string& path, const std::string& hint) {
  return read_valid_config<Config>(read_config_json(path), {path, hint, "", false});
}

template <typename Config>
nlohmann::json write_config(Config config) {
  JsonConfigWriter writer;
  visit_fields(writer, config);
  return writer.result();
}

template <typename Config>
std::set<std::string> fields_that_may_change() {
  Config config;
  MayChangeCollector collector;
  visit_fields(collector, config);
  return collector.result();
}

template <typename Config>
std::string describe_config(Config config) {
  HelpWriter writer;
  visit_fields(writer, config);
  return writer.result();
}

}  // namespace nec::train
