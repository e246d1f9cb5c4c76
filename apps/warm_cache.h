// What a long-lived `nec worker` keeps between the commands it runs: loaded models and prepared rigs, each
// under a key of what it was made from (paths with their files' sizes and times, options), the least recently
// used dropped beyond a cap. A one-shot command has the cache off: every object is made afresh, kept nowhere.
//
//   enable_warm_cache({/*models=*/4, /*rigs=*/32});          // nec worker only
//   std::shared_ptr<gpt::GeneratorSession> gpt = warm<gpt::GeneratorSession>(WarmKind::Model,
//       "gpt " + files_stamp(dir), [&] { return gpt::open_generator(dir, glove); });
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <typeinfo>

namespace nec::app {

enum class WarmKind { Model, Rig };

struct WarmCacheLimits {
  size_t models = 4;  // loaded models kept (a GPT with its tokenizer counts one)
  size_t rigs = 32;   // prepared rigs kept
};

void enable_warm_cache(const WarmCacheLimits& limits);

// "path size mtime" of a file, or of every file below a folder (a model directory), sorted; "path missing" when
// there is none: a key that changes whenever the files do, so a retrained model is loaded again.
std::string files_stamp(const std::string& path);

// The shared object made by `make` for `key` of kind `kind` (kept for the next command when the cache is on).
std::shared_ptr<void> warm_object(WarmKind kind, const std::string& key, const std::function<std::shared_ptr<void>()>& make);

template <class T, class Make>
std::shared_ptr<T> warm(WarmKind kind, const std::string& key, Make make) {
  return std::static_pointer_cast<T>(warm_object(kind, std::string(typeid(T).name()) + "\n" + key,
                                                 [&] { return std::shared_ptr<void>(std::make_shared<T>(make())); }));
}

}  // namespace nec::app
