// The visitors over a config's one field list: JSON reader and writer, the
// fields a resumed run may change, and the --help lines.
#include "nec/train/config_fields.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <algorithm>
#include <limits>
#include <type_traits>

namespace nec::train {
namespace {

using nlohmann::json;

template <typename... Lambdas>
struct Overloaded : Lambdas... {
  using Lambdas::operator()...;
};
template <typename... Lambdas>
Overloaded(Lambdas...) -> Overloaded<Lambdas...>;

json value_as_json(const FieldValue& value) {
  return std::visit([](auto* v) { return json(*v); }, value);
}

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

}  // namespace

JsonConfigReader::JsonConfigReader(const json& root, ReadOptions options) : options_(std::move(options)) {
  if (!root.is_object()) {
    const std::string what = options_.prefix.empty() ? "a config" : "field '" + options_.prefix.substr(0, options_.prefix.size() - 1) + "'";
    throw InputError(options_.file, 0, what + " must be a JSON object" + (options_.hint.empty() ? "" : "; " + options_.hint));
  }
  levels_.push_back(Level{&root, options_.prefix, {}});
}

void JsonConfigReader::fail(const std::string& name, const std::string& problem) const {
  throw InputError(options_.file, 0,
                   "field '" + name + "' " + problem + (options_.hint.empty() ? "" : "; " + options_.hint));
}

void JsonConfigReader::visit(const FieldInfo& info, FieldValue value) {
  Level& level = levels_.back();
  level.declared.push_back(info.name);
  const std::string name = level.prefix + info.name;
  const auto it = level.object->find(info.name);
  if (it == level.object->end()) {
    if (options_.required && info.in_checkpoints == InCheckpoints::kRequired) fail(name, "is missing");
    return;
  }
  const json& v = *it;
  std::visit(Overloaded{
                 [&](bool* out) {
                   if (!v.is_boolean()) fail(name, "must be true or false");
                   *out = v.get<bool>();
                 },
                 [&](uint64_t* out) {
                   if (!v.is_number_unsigned()) fail(name, "must be a non-negative integer");
                   *out = v.get<uint64_t>();
                 },
                 [&](double* out) {
                   if (!v.is_number()) fail(name, "must be a number");
                   *out = v.get<double>();
                 },
                 [&](std::string* out) {
                   if (!v.is_string()) fail(name, "must be a string");
                   const std::string text = v.get<std::string>();
                   if (info.choices && std::find(info.choices->begin(), info.choices->end(), text) == info.choices->end()) {
                     fail(name, "is '" + text + "', not one of: " + joined(*info.choices));
                   }
                   *out = text;
                 },
                 [&](std::vector<std::string>* out) {
                   if (!v.is_array()) fail(name, "must be a list of strings");
                   std::vector<std::string> items;
                   for (const json& item : v) {
                     if (!item.is_string()) fail(name, "must be a list of strings");
                     items.push_back(item.get<std::string>());
                   }
                   *out = std::move(items);
                 },
                 [&](auto* out) {  // int, int64_t
                   using T = std::remove_pointer_t<decltype(out)>;
                   if (!v.is_number_integer()) fail(name, "must be an integer");
                   const bool too_big = v.is_number_unsigned() &&
                                        v.get<uint64_t>() > static_cast<uint64_t>(std::numeric_limits<T>::max());
                   const int64_t n = too_big ? 0 : v.get<int64_t>();
                   if (too_big || n < std::numeric_limits<T>::min() || n > std::numeric_limits<T>::max()) {
                     fail(name, "is out of range");
                   }
                   *out = static_cast<T>(n);
                 },
             },
             value);
}

void JsonConfigReader::enter(const char* name, const char*) {
  static const json kEmpty = json::object();
  Level& level = levels_.back();
  level.declared.push_back(name);
  const std::string dotted = level.prefix + name;
  const auto it = level.object->find(name);
  const json* object = &kEmpty;
  if (it == level.object->end()) {
    if (options_.required) fail(dotted, "is missing");
  } else {
    if (!it->is_object()) fail(dotted, "must be an object");
    object = &*it;
  }
  levels_.push_back(Level{object, dotted + ".", {}});
}

void JsonConfigReader::check_declared(const Level& level) const {
  for (auto it = level.object->begin(); it != level.object->end(); ++it) {
    // "comment": a note for people, allowed in every object of every config.
    if (it.key() == "comment") continue;
    if (std::find(level.declared.begin(), level.declared.end(), it.key()) == level.declared.end()) {
      fail(level.prefix + it.key(), "is not a known field (known here: " + joined(level.declared) + ")");
    }
  }
}

void JsonConfigReader::leave() {
  check_declared(levels_.back());
  levels_.pop_back();
}

void JsonConfigReader::finish() { check_declared(levels_.front()); }

void JsonConfigWriter::visit(const FieldInfo& info, FieldValue value) { levels_.back()[info.name] = value_as_json(value); }

void JsonConfigWriter::enter(const char* name, const char*) {
  names_.push_back(name);
  levels_.push_back(json::object());
}

void JsonConfigWriter::leave() {
  json object = std::move(levels_.back());
  levels_.pop_back();
  levels_.back()[names_.back()] = std::move(object);
  names_.pop_back();
}

void DottedVisitor::enter(const char* name, const char*) {
  lengths_.push_back(prefix_.size());
  prefix_ += std::string(name) + ".";
}

void DottedVisitor::leave() {
  prefix_.resize(lengths_.back());
  lengths_.pop_back();
}

void MayChangeCollector::visit(const FieldInfo& info, FieldValue) {
  if (info.on_resume == OnResume::kMayChange) names_.insert(prefix() + info.name);
}

void HelpWriter::visit(const FieldInfo& info, FieldValue value) {
  std::string help = info.help;
  if (info.choices) help += " (" + joined(*info.choices) + ")";
  if (info.on_resume == OnResume::kMayChange) help += "; may change on --resume";
  lines_.emplace_back(prefix() + info.name + " = " + value_as_json(value).dump(), help);
}

void HelpWriter::enter(const char* name, const char* help) {
  lines_.emplace_back(prefix() + name + ".", help);
  DottedVisitor::enter(name, help);
}

nlohmann::json read_config_json(const std::string& path) {
  try {
    return nlohmann::json::parse(read_file(path, size_t{1} << 24));
  } catch (const nlohmann::json::parse_error& error) {
    throw InputError(path, 0, std::string("not valid JSON: ") + error.what());
  }
}

void visit_cadence_fields(ConfigVisitor& v, int64_t& steps, int64_t& log_every, int64_t& validate_every,
                          int64_t& checkpoint_every) {
  v.field("steps", steps, "the step training ends at", OnResume::kMayChange);
  v.field("log_every", log_every, "progress line every N steps off a terminal; 0 = only the last", OnResume::kMayChange);
  v.field("validate_every", validate_every, "validation every N steps and at the end; 0 = never", OnResume::kMayChange);
  v.field("checkpoint_every", checkpoint_every, "checkpoint every N steps and at the end; 0 = only at the end",
          OnResume::kMayChange);
}

std::string HelpWriter::result() const {
  size_t width = 0;
  for (const auto& line : lines_) width = std::max(width, line.first.size());
  width = std::min<size_t>(width, 44);
  std::string out;
  for (const auto& [field, help] : lines_) {
    out += "  " + field;
    out += field.size() < width ? std::string(width - field.size(), ' ') : std::string(1, ' ');
    out += "  " + help + "\n";
  }
  return out;
}

}  // namespace nec::train
