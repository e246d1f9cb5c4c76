// Checkpoint directory building blocks: config.json reading, tensor archives, atomic swap.
#include "nec/train/checkpoint_io.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/hash.h"

#include <c10/util/Exception.h>
#include <torch/torch.h>

#include <filesystem>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

namespace nec::train {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kConfigFile = "config.json";

std::vector<std::pair<std::string, at::Tensor>> named_tensors(torch::nn::Module& module) {
  std::vector<std::pair<std::string, at::Tensor>> out;
  for (const auto& item : module.named_parameters()) out.emplace_back(item.key(), item.value());
  for (const auto& item : module.named_buffers()) out.emplace_back(item.key(), item.value());
  return out;
}

std::string shape_text(at::IntArrayRef sizes) {
  std::string text = "[";
  for (size_t i = 0; i < sizes.size(); ++i) text += (i ? ", " : "") + std::to_string(sizes[i]);
  return text + "]";
}

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

fs::path sibling(const fs::path& dir, const std::string& tag) {
  std::random_device entropy;
  return dir.parent_path() / ("." + dir.filename().string() + "." + tag + std::to_string(entropy()));
}

}  // namespace

const json& JsonFields::object(const json& parent, const std::string& key, const std::string& where) const {
  const json& value = field(parent, key, where);
  if (!value.is_object()) fail_type(where + key, "an object");
  return value;
}

void JsonFields::fail(const std::string& problem) const { throw InputError(file_, 0, problem); }

std::string JsonFields::entry(const json& root, const std::string& key) const {
  std::string name;
  read(root, key, "", name);
  if (name.empty() || std::filesystem::path(name).has_parent_path() || name == "." || name == "..") {
    fail("field '" + key + "' must name an entry inside the checkpoint directory, got '" + name + "'; " + hint_);
  }
  return name;
}

const json& JsonFields::field(const json& parent, const std::string& key, const std::string& where) const {
  const auto it = parent.find(key);
  if (it == parent.end()) fail("field '" + where + key + "' is missing; " + hint_);
  return *it;
}

void JsonFields::fail_type(const std::string& name, const std::string& expected) const {
  fail("field '" + name + "' must be " + expected + "; " + hint_);
}

CheckpointConfig read_checkpoint_config(const std::string& dir, const std::string& format, int version,
                                        const std::string& what, const std::string& hint) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, 0, "no such checkpoint directory; " + hint);
  CheckpointConfig config;
  config.path = (fs::path(dir) / kConfigFile).string();
  config.hint = hint;
  if (!fs::exists(config.path, ec)) {
    throw InputError(config.path, 0, "missing: not " + what + "; " + hint);
  }
  const JsonFields fields = config.fields();
  try {
    config.root = json::parse(read_file(config.path, size_t{1} << 24));
  } catch (const json::parse_error& error) {
    fields.fail(std::string("not valid JSON (") + error.what() + "); the checkpoint is damaged, " + hint);
  }
  json& root = config.root;
  if (!root.is_object()) fields.fail("not " + what + " (no JSON object); " + hint);
  const auto found_format = root.find("format");
  if (found_format == root.end() || !found_format->is_string() || *found_format != format) {
    const std::string found =
        found_format == root.end()
            ? "none"
            : "'" + (found_format->is_string() ? found_format->get<std::string>() : found_format->dump()) + "'";
    fields.fail("not " + what + " (format " + found + ", expected '" + format + "'); " + hint);
  }
  const auto found_version = root.find("version");
  if (found_version == root.end() || !found_version->is_number_integer()) {
    fields.fail("field 'version' is missing or not an integer; the checkpoint is damaged, " + hint);
  }
  if (found_version->get<int64_t>() != version) {
    fields.fail("was written by format version " + std::to_string(found_version->get<int64_t>()) +
                "; this nec reads version " + std::to_string(version) +
                ": load it with the nec that wrote it, or retrain (" + hint + ")");
  }
  return config;
}

void save_module_tensors(torch::nn::Module& module, const std::string& path) {
  torch::serialize::OutputArchive archive;
  {
    torch::NoGradGuard no_grad;
    for (const auto& [name, tensor] : named_tensors(module)) archive.write(name, tensor.detach().to(torch::kCPU));
  }
  try {
    archive.save_to(path);
  } catch (const c10::Error& error) {
    throw std::runtime_error(path + ": cannot write the tensors: " + first_line(error.what()));
  }
}

void load_module_tensors(torch::nn::Module& module, const std::string& path, const std::string& hint) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, 0, "missing; the checkpoint is incomplete, " + hint);
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path, torch::kCPU);
  } catch (const c10::Error& error) {
    throw InputError(path, 0, "cannot read the tensors (truncated or corrupt?): " + first_line(error.what()) + "; " + hint);
  }
  const auto expected = named_tensors(module);
  std::vector<std::string> stored;
  try {
    stored = archive.keys();
  } catch (const c10::Error& error) {
    throw InputError(path, 0, "cannot list the tensors: " + first_line(error.what()));
  }
  if (stored.size() != expected.size()) {
    throw InputError(path, 0,
                     "holds " + std::to_string(stored.size()) + " tensors, but the architecture in config.json has " +
                         std::to_string(expected.size()) + "; config.json and the tensors do not belong together");
  }
  torch::NoGradGuard no_grad;
  for (const auto& [name, tensor] : expected) {
    at::Tensor value;
    bool found = false;
    try {
      found = archive.try_read(name, value);
    } catch (const c10::Error& error) {
      throw InputError(path, 0, "cannot read tensor '" + name + "': " + first_line(error.what()));
    }
    if (!found) {
      throw InputError(path, 0, "has no tensor '" + name +
                                    "' that the architecture in config.json needs; config.json and the tensors "
                                    "do not belong together");
    }
    if (value.sizes() != tensor.sizes() || value.scalar_type() != tensor.scalar_type()) {
      throw InputError(path, 0, "tensor '" + name + "' is " + shape_text(value.sizes()) + " " +
                                    std::string(c10::toString(value.scalar_type())) + ", config.json implies " +
                                    shape_text(tensor.sizes()) + " " + c10::toString(tensor.scalar_type()) +
                                    "; config.json and the tensors do not belong together");
    }
    tensor.copy_(value);
  }
}

void copy_module_tensors(torch::nn::Module& from, torch::nn::Module& to) {
  torch::NoGradGuard no_grad;
  auto parameters = from.named_parameters();
  for (auto& item : to.named_parameters()) item.value().copy_(parameters[item.key()]);
  auto buffers = from.named_buffers();
  for (auto& item : to.named_buffers()) item.value().copy_(buffers[item.key()]);
}

void write_checkpoint_directory(const std::string& dir, const std::string& what,
                                const std::function<void(const std::string& temp_dir)>& fill) {
  fs::path target = fs::path(dir);
  if (target.filename().empty()) target = target.parent_path();  // "runs/owo/" -> "runs/owo"
  std::error_code ec;
  const bool exists = fs::exists(target, ec);
  if (exists && (!fs::is_directory(target, ec) ||
                 (!fs::is_empty(target, ec) && !fs::exists(target / kConfigFile, ec)))) {
    throw std::runtime_error(dir + ": exists and is not " + what + " directory; not replacing it");
  }
  if (!target.parent_path().empty()) fs::create_directories(target.parent_path(), ec);

  const fs::path temp = sibling(target, "tmp");
  try {
    if (!fs::create_directory(temp, ec)) throw std::runtime_error(temp.string() + ": cannot create: " + ec.message());
    fill(temp.string());
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(temp)) {
      if (entry.is_regular_file() || entry.is_directory()) sync_to_disk(entry.path().string());
    }
    sync_to_disk(temp.string());
    fs::path old;
    if (exists) {
      old = sibling(target, "old");
      fs::rename(target, old, ec);
      if (ec) throw std::runtime_error(dir + ": cannot move the old checkpoint aside: " + ec.message());
    }
    fs::rename(temp, target, ec);
    if (ec) {
      std::error_code ignored;
      if (!old.empty()) fs::rename(old, target, ignored);
      throw std::runtime_error(dir + ": cannot move the written checkpoint into place: " + ec.message());
    }
    sync_to_disk(target.parent_path().empty() ? "." : target.parent_path().string());
    if (!old.empty()) remove_tree(old.string());
  } catch (...) {
    remove_tree(temp.string());
    throw;
  }
}

void check_output_directory(const std::string& dir, bool resume, bool force) {
  std::error_code ec;
  const bool exists = fs::exists(dir, ec);
  const bool checkpoint = fs::exists(fs::path(dir) / kConfigFile, ec);
  if (resume) {
    if (!checkpoint) {
      throw InputError(dir, 0, "no checkpoint to resume; give the --out of an earlier run, or leave out --resume");
    }
    return;
  }
  if (checkpoint) {
    if (force) return;
    throw InputError(dir, 0,
                     "already holds a checkpoint; pass --resume to continue it, --force to replace it, or choose "
                     "another --out");
  }
  if (exists && (!fs::is_directory(dir, ec) || !fs::is_empty(dir, ec))) {
    throw InputError(dir, 0, "exists and is not a checkpoint directory; choose another --out");
  }
}

uint64_t checkpoint_key(const std::string& dir) {
  uint64_t key = kFnv1aOffset;
  for (const char* file : {"config.json", "tensors.pt"}) {
    key = fnv1a64(read_file((fs::path(dir) / file).string(), size_t{1} << 32), key);
  }
  return key;
}

}  // namespace nec::train
