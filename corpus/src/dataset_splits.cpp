// Dataset splits: train / validation / test by source, held-out datasets and skeletons.
#include "nec/corpus/dataset.h"

#include "nec/motion/hash.h"
#include "nec/motion/random.h"

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

namespace nec {

namespace {

void check_fraction(double value, const char* name) {
  if (!(value >= 0.0 && value <= 1.0)) {
    throw std::invalid_argument(std::string("SplitOptions: ") + name + " = " + std::to_string(value) + " is outside [0, 1]");
  }
}

// Where a source goes among the non-held-out sources: a hash of (seed, key).
uint64_t source_rank(uint64_t seed, const std::string& key) {
  char seed_bytes[8];
  for (int i = 0; i < 8; ++i) seed_bytes[i] = static_cast<char>(seed >> (8 * i));
  return mix64(fnv1a64(key, fnv1a64(std::string_view(seed_bytes, 8))));
}

// The longest leading folder ("a/b/") of two folder paths that end with '/'.
std::string shared_folder(const std::string& a, const std::string& b) {
  size_t same = 0;
  while (same < a.size() && same < b.size() && a[same] == b[same]) ++same;
  if (same == 0) return "";
  const size_t slash = a.rfind('/', same - 1);
  return slash == std::string::npos ? "" : a.substr(0, slash + 1);
}

std::string list_for_message(const std::vector<std::string>& names) {
  std::string out;
  const size_t shown = std::min<size_t>(names.size(), 20);
  for (size_t i = 0; i < shown; ++i) out += (i ? ", " : "") + names[i];
  if (names.size() > shown) out += ", ... (" + std::to_string(names.size()) + " in all)";
  return out;
}

}  // namespace

std::string_view split_name(Split split) {
  switch (split) {
    case Split::Train: return "train";
    case Split::Val: return "val";
    case Split::Test: return "test";
  }
  return "train";
}

std::optional<Split> parse_split(std::string_view name) {
  if (name == "train") return Split::Train;
  if (name == "val") return Split::Val;
  if (name == "test") return Split::Test;
  return std::nullopt;
}

void SplitOptions::validate() const {
  check_fraction(val_fraction, "val_fraction");
  check_fraction(test_fraction, "test_fraction");
  if (val_fraction + test_fraction > 1.0) {
    throw std::invalid_argument("SplitOptions: val_fraction + test_fraction = " +
                                std::to_string(val_fraction + test_fraction) + " exceeds 1");
  }
}

bool wildcard_match(std::string_view pattern, std::string_view text) {
  size_t p = 0, t = 0;
  size_t star = std::string_view::npos, resume = 0;
  while (t < text.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || pattern[p] == text[t])) {
      ++p;
      ++t;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = t;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      t = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

std::vector<int> held_out_skeletons(const DatasetCache& cache, const SplitOptions& options) {
  const int count = static_cast<int>(cache.skeletons.size());
  std::vector<bool> held(count, false);
  for (const std::string& pattern : options.held_out_skeletons) {
    bool matched = false;
    for (int s = 0; s < count; ++s) {
      if (wildcard_match(pattern, cache.skeletons[s].name) || wildcard_match(pattern, cache.skeletons[s].hash)) {
        held[s] = true;
        matched = true;
      }
    }
    if (!matched) {
      std::vector<std::string> names;
      for (const CachedSkeleton& s : cache.skeletons) names.push_back(s.name);
      throw std::invalid_argument("held-out skeleton '" + pattern + "' matches no skeleton; the skeletons are: " +
                                  list_for_message(names));
    }
  }
  for (const std::string& dataset : options.held_out_datasets) {
    bool matched = false;
    for (const CacheClip& c : cache.clips) {
      if (c.dataset == dataset) {
        held.at(c.skeleton) = true;
        matched = true;
      }
    }
    if (!matched) {
      std::set<std::string> datasets;
      for (const CacheClip& c : cache.clips) datasets.insert(c.dataset);
      const std::vector<std::string> names(datasets.begin(), datasets.end());
      throw std::invalid_argument("held-out dataset '" + dataset + "' has no clips; the datasets are: " +
                                  list_for_message(names));
    }
  }
  std::vector<int> out;
  for (int s = 0; s < count; ++s) {
    if (held[s]) out.push_back(s);
  }
  return out;
}

std::vector<Split> assign_splits(const DatasetCache& cache, const SplitOptions& options) {
  options.validate();
  std::vector<bool> held(cache.skeletons.size(), false);
  for (int s : held_out_skeletons(cache, options)) held[s] = true;

  // Clips grouped by source file; a group goes to one split as a whole.
  std::map<std::string, std::vector<int>> groups;
  for (int i = 0; i < cache.clip_count(); ++i) groups[cache.clips[i].source].push_back(i);

  // A source ranks by its dataset and its path below the folder that holds all of
  // that dataset's files, so that "../data/dog" and "/home/me/data/dog" split alike.
  std::map<std::string, std::string> common_folder;  // per dataset, ends with '/' or is empty
  for (const CacheClip& clip : cache.clips) {
    const std::string folder = clip.source.substr(0, clip.source.rfind('/') + 1);
    const auto [it, inserted] = common_folder.emplace(clip.dataset, folder);
    if (!inserted) it->second = shared_folder(it->second, folder);
  }
  auto rank_key = [&](const CacheClip& clip) {
    return clip.dataset + ":" + clip.source.substr(common_folder.at(clip.dataset).size());
  };

  std::vector<Split> splits(cache.clips.size(), Split::Train);
  struct Ranked {
    uint64_t rank;
    const std::string* source;
    const std::vector<int>* clips;
  };
  std::vector<Ranked> free_groups;
  size_t free_clips = 0;
  for (const auto& [source, members] : groups) {
    const bool held_out = std::any_of(members.begin(), members.end(), [&](int i) { return held.at(cache.clips[i].skeleton); });
    if (held_out) {
      for (int i : members) splits[i] = Split::Test;
    } else {
      free_groups.push_back({source_rank(options.seed, rank_key(cache.clips[members.front()])), &source, &members});
      free_clips += members.size();
    }
  }
  std::sort(free_groups.begin(), free_groups.end(), [](const Ranked& a, const Ranked& b) {
    return a.rank != b.rank ? a.rank < b.rank : *a.source < *b.source;
  });
  // A group joins test (then val) when that brings the split's clip count
  // closer to its target: count + size / 2 < target.
  const double test_target = options.test_fraction * static_cast<double>(free_clips);
  const double val_target = options.val_fraction * static_cast<double>(free_clips);
  double test_count = 0.0, val_count = 0.0;
  for (const Ranked& group : free_groups) {
    const double size = static_cast<double>(group.clips->size());
    Split split = Split::Train;
    if (test_count + size / 2.0 < test_target) {
      split = Split::Test;
      test_count += size;
    } else if (val_count + size / 2.0 < val_target) {
      split = Split::Val;
      val_count += size;
    }
    for (int i : *group.clips) splits[i] = split;
  }
  return splits;
}

}  // namespace nec
