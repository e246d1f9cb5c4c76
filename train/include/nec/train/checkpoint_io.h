// Building blocks of checkpoint directories (DESIGN.md, Files the tool writes),
// shared by every model's checkpoint format: checked reading of config.json,
// named-tensor archives checked against a module, the atomic swap of a whole
// directory (every file flushed to disk first), and the check of a training
// run's output directory.
//
//   write_checkpoint_directory("runs/tat", "a TAT checkpoint", [&](const std::string& temp) {
//     write_file_atomic(temp + "/config.json", config.dump(2));
//     save_module_tensors(*model, temp + "/tensors.pt");
//   });
//   CheckpointConfig c = read_checkpoint_config("runs/tat", "nec-tat", 1, "a TAT checkpoint",
//                                               "run `nec train tat` to make one");
//   JsonFields f = c.fields();  int64_t step;  f.read(c.root, "training_step", "", step);
//   load_module_tensors(*model, "runs/tat/tensors.pt", c.hint);
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>

namespace torch::nn {
class Module;
}

namespace nec::train {

// Reads fields of a JSON file (a checkpoint's config.json, a training
// config); every problem is an InputError(file, 0, "field 'a.b' ...; <hint>").
class JsonFields {
 public:
  JsonFields(std::string file, std::string hint) : file_(std::move(file)), hint_(std::move(hint)) {}

  // `where` is the dotted prefix of `key` for messages, e.g. "encoder.".
  const nlohmann::json& object(const nlohmann::json& parent, const std::string& key, const std::string& where) const;
  template <typename T>
  void read(const nlohmann::json& parent, const std::string& key, const std::string& where, T& out) const {
    const nlohmann::json& value = field(parent, key, where);
    if constexpr (std::is_same_v<T, bool>) {
      if (!value.is_boolean()) fail_type(where + key, "true or false");
    } else if constexpr (std::is_integral_v<T>) {
      if (!value.is_number_integer()) fail_type(where + key, "an integer");
    } else if constexpr (std::is_floating_point_v<T>) {
      if (!value.is_number()) fail_type(where + key, "a number");
    } else {
      if (!value.is_string()) fail_type(where + key, "a string");
    }
    out = value.get<T>();
  }
  // A top-level string naming a file or folder inside the checkpoint directory
  // (no path separators), e.g. "tensors.pt"; fails otherwise.
  std::string entry(const nlohmann::json& root, const std::string& key) const;
  [[noreturn]] void fail(const std::string& problem) const;
  const std::string& file() const { return file_; }
  const std::string& hint() const { return hint_; }

 private:
  const nlohmann::json& field(const nlohmann::json& parent, const std::string& key, const std::string& where) const;
  [[noreturn]] void fail_type(const std::string& name, const std::string& expected) const;
  std::string file_, hint_;
};

struct CheckpointConfig {
  std::string path;     // <dir>/config.json
  std::string hint;     // what to do about a problem, e.g. "run `nec train owo` to make one"
  nlohmann::json root;  // the parsed object, format and version checked

  // Field problems end with "the checkpoint is damaged, <hint>".
  JsonFields fields() const { return JsonFields(path, "the checkpoint is damaged, " + hint); }
};

// Parses <dir>/config.json and checks "format" == format and "version" == version.
// Throws InputError naming the directory or file for a missing directory, a
// missing/invalid file, a foreign format, or another version.
// `what` names the kind in messages, e.g. "an OwO checkpoint".
CheckpointConfig read_checkpoint_config(const std::string& dir, const std::string& format, int version,
                                        const std::string& what, const std::string& hint);

// Every parameter and buffer of `module` by dotted name, to a torch archive at `path`.
void save_module_tensors(torch::nn::Module& module, const std::string& path);
// Copies the archive's tensors into `module` after checking that names, count,
// shapes and dtypes match exactly; InputError(path, ...) otherwise (nothing is
// half-loaded into a module the caller keeps only when this returns).
void load_module_tensors(torch::nn::Module& module, const std::string& path, const std::string& hint);

// Copies every parameter and buffer of `from` into the same-named one of `to`
// (modules of one architecture: a loaded checkpoint into a trainer's model).
void copy_module_tensors(torch::nn::Module& from, torch::nn::Module& to);

// Creates a temporary sibling directory of `dir`, lets `fill` write into it,
// flushes every file in it to disk, then swaps it into place (an existing checkpoint is moved aside first and
// removed only after the swap), so `dir` is always the old or the new
// checkpoint, never a mixture. `what` names the kind in messages, e.g. "an OwO
// checkpoint". Refuses (std::runtime_error) to replace a non-empty directory
// without a config.json. Anything `fill` throws removes the temporary and is rethrown.
void write_checkpoint_directory(const std::string& dir, const std::string& what,
                                const std::function<void(const std::string& temp_dir)>& fill);

// A hash of the checkpoint's config.json and tensors.pt: what files derived
// from a model (retrieval indexes, GPT token sets) are keyed by. InputError
// naming the file when one cannot be read.
uint64_t checkpoint_key(const std::string& dir);

// The --out of a training run before anything is written: with `resume` it
// must hold a checkpoint (a config.json); without, it must not hold one unless
// `force` (the run then replaces it at its first checkpoint), and otherwise be
// absent or an empty directory. Throws InputError(dir, 0, ...) saying which
// flag to pass; touches nothing.
void check_output_directory(const std::string& dir, bool resume, bool force);

}  // namespace nec::train
