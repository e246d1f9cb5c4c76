// The worker's cache of models and prepared rigs: one least-recently-used list per kind.
#include "warm_cache.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <list>
#include <mutex>
#include <system_error>
#include <utility>
#include <vector>

namespace nec::app {
namespace {

namespace fs = std::filesystem;

struct Entry {
  std::string key;
  std::shared_ptr<void> object;
};

struct Cache {
  std::mutex lock;
  bool enabled = false;
  WarmCacheLimits limits;
  std::list<Entry> models, rigs;  // most recently used first

  std::list<Entry>& list(WarmKind kind) { return kind == WarmKind::Model ? models : rigs; }
  size_t cap(WarmKind kind) const { return kind == WarmKind::Model ? limits.models : limits.rigs; }
};

Cache& cache() {
  static Cache instance;
  return instance;
}

std::string stamp_of(const fs::path& file) {
  std::error_code error;
  const auto size = fs::file_size(file, error);
  const auto time = fs::last_write_time(file, error);
  if (error) return file.string() + " missing";
  return fmt::format("{} {} {}", file.string(), size, time.time_since_epoch().count());
}

}  // namespace

void enable_warm_cache(const WarmCacheLimits& limits) {
  Cache& c = cache();
  std::lock_guard<std::mutex> hold(c.lock);
  c.enabled = true;
  c.limits = limits;
}

std::string files_stamp(const std::string& path) {
  std::error_code error;
  if (!fs::is_directory(path, error)) return stamp_of(path);
  std::vector<std::string> stamps;
  for (auto it = fs::recursive_directory_iterator(path, error); !error && it != fs::recursive_directory_iterator(); it.increment(error)) {
    if (it->is_regular_file(error)) stamps.push_back(stamp_of(it->path()));
  }
  std::sort(stamps.begin(), stamps.end());
  std::string out = fs::path(path).string();
  for (const std::string& s : stamps) out += "\n" + s;
  return out;
}

std::shared_ptr<void> warm_object(WarmKind kind, const std::string& key, const std::function<std::shared_ptr<void>()>& make) {
  Cache& c = cache();
  {
    std::lock_guard<std::mutex> hold(c.lock);
    if (!c.enabled) return make();
    std::list<Entry>& list = c.list(kind);
    const auto found = std::find_if(list.begin(), list.end(), [&](const Entry& e) { return e.key == key; });
    if (found != list.end()) {
      list.splice(list.begin(), list, found);
      return found->object;
    }
  }
  // Made outside the lock (a model loads for a second); a failure keeps nothing.
  std::shared_ptr<void> made = make();
  std::lock_guard<std::mutex> hold(c.lock);
  std::list<Entry>& list = c.list(kind);
  list.push_front({key, made});
  while (list.size() > std::max<size_t>(1, c.cap(kind))) list.pop_back();
  return made;
}

}  // namespace nec::app
