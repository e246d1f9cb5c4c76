// Token files (JSON).
#include "nec/tat/tokens.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/train/checkpoint_io.h"

#include <nlohmann/json.hpp>

namespace nec::tat {
namespace {

using nlohmann::json;
constexpr const char* kHint = "make token files with `nec encode`";

}  // namespace

void write_tokens(const std::string& path, const TokenFile& t) {
  // One token step per line keeps the files readable and diffable.
  std::string rows = "[";
  for (int s = 0; s < t.steps(); ++s) {
    rows += s ? ",\n  [" : "\n  [";
    for (int r = 0; r < t.layers; ++r) {
      rows += (r ? ", " : "") + std::to_string(t.codes[static_cast<size_t>(s) * t.layers + r]);
    }
    rows += "]";
  }
  rows += "\n ]";
  constexpr const char* kPlaceholder = "\"@tokens@\"";
  const json root = {{"format", kTokenFileFormat},
                     {"version", kTokenFileVersion},
                     {"fps", t.fps},
                     {"frames", t.frames},
                     {"downsampling", t.downsampling},
                     {"codebook", {{"layers", t.layers}, {"size", t.codebook_size}}},
                     {"model", {{"kind", t.model_kind}, {"training_step", t.training_step}}},
                     {"source",
                      {{"file", t.source_file},
                       {"joints", t.source_joints},
                       {"scale", t.source_scale},
                       {"heading_degrees", t.heading_degrees}}},
                     {"tokens", "@tokens@"}};
  std::string text = root.dump(1);
  text.replace(text.find(kPlaceholder), std::string(kPlaceholder).size(), rows);
  write_file_atomic(path, text + "\n");
}

TokenFile read_tokens(const std::string& path) {
  const train::JsonFields fields(path, kHint);
  json root;
  try {
    root = json::parse(read_file(path, size_t{1} << 30));
  } catch (const json::parse_error& error) {
    fields.fail(std::string("not valid JSON (") + error.what() + "); " + kHint);
  }
  if (!root.is_object()) fields.fail(std::string("not a token file (no JSON object); ") + kHint);
  std::string format;
  if (!root.contains("format")) fields.fail(std::string("not a token file (no 'format'); ") + kHint);
  fields.read(root, "format", "", format);
  if (format != kTokenFileFormat) fields.fail("not a token file (format '" + format + "'); " + kHint);
  int version = 0;
  fields.read(root, "version", "", version);
  if (version != kTokenFileVersion) {
    fields.fail("token file version " + std::to_string(version) + "; this nec reads version " +
                std::to_string(kTokenFileVersion));
  }
  TokenFile t;
  fields.read(root, "fps", "", t.fps);
  fields.read(root, "frames", "", t.frames);
  fields.read(root, "downsampling", "", t.downsampling);
  const json& codebook = fields.object(root, "codebook", "");
  fields.read(codebook, "layers", "codebook.", t.layers);
  fields.read(codebook, "size", "codebook.", t.codebook_size);
  const json& model = fields.object(root, "model", "");
  fields.read(model, "kind", "model.", t.model_kind);
  fields.read(model, "training_step", "model.", t.training_step);
  const json& source = fields.object(root, "source", "");
  fields.read(source, "file", "source.", t.source_file);
  fields.read(source, "joints", "source.", t.source_joints);
  fields.read(source, "scale", "source.", t.source_scale);
  fields.read(source, "heading_degrees", "source.", t.heading_degrees);
  if (t.fps <= 0 || t.frames < 1 || t.downsampling < 1 || t.layers < 1 || t.codebook_size < 1) {
    fields.fail("fps, frames, downsampling, codebook.layers and codebook.size must be positive");
  }
  const auto tokens = root.find("tokens");
  if (tokens == root.end() || !tokens->is_array()) fields.fail("field 'tokens' must be an array of token steps");
  const int steps = (t.frames + t.downsampling - 1) / t.downsampling;
  if (static_cast<int>(tokens->size()) != steps) {
    fields.fail("has " + std::to_string(tokens->size()) + " token steps; " + std::to_string(t.frames) +
                " frames at downsampling " + std::to_string(t.downsampling) + " need " + std::to_string(steps));
  }
  t.codes.reserve(static_cast<size_t>(steps) * t.layers);
  for (int s = 0; s < steps; ++s) {
    const json& row = (*tokens)[s];
    if (!row.is_array() || static_cast<int>(row.size()) != t.layers) {
      fields.fail("token step " + std::to_string(s) + " must be a list of " + std::to_string(t.layers) + " codes");
    }
    for (const json& code : row) {
      if (!code.is_number_integer() || code.get<int64_t>() < 0 || code.get<int64_t>() >= t.codebook_size) {
        fields.fail("token step " + std::to_string(s) + " has code " + code.dump() + "; codes are 0.." +
                    std::to_string(t.codebook_size - 1));
      }
      t.codes.push_back(code.get<int32_t>());
    }
  }
  return t;
}

}  // namespace nec::tat
