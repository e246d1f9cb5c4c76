// The registry of motion file formats and the FILE#ANIMATION selector.
#include "nec/motion/clip_file.h"

#include "nec/motion/bvh.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/frame_rate.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <mutex>

namespace nec {
namespace {

std::mutex& registry_mutex() {
  static std::mutex mutex;
  return mutex;
}

std::vector<ClipFormat>& registry() {
  static std::vector<ClipFormat> formats;
  return formats;
}

std::vector<ClipWriter>& writers() {
  static std::vector<ClipWriter> formats;
  return formats;
}

template <class Format>
const Format* find_format(const std::vector<Format>& formats, const std::string& ext) {
  for (auto it = formats.rbegin(); it != formats.rend(); ++it) {
    if (std::find(it->extensions.begin(), it->extensions.end(), ext) != it->extensions.end()) return &*it;
  }
  return nullptr;
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// The reader of `ext`; nullptr for BVH (read here) or an unknown extension.
const ClipFormat* format_for(const std::string& ext) {
  std::lock_guard<std::mutex> lock(registry_mutex());
  return find_format(registry(), ext);
}

const ClipWriter* writer_for(const std::string& ext) {
  std::lock_guard<std::mutex> lock(registry_mutex());
  return find_format(writers(), ext);
}

// FILE#NAME -> {FILE, NAME}; a path that exists as it is, or has no '#', -> {path, ""}.
std::pair<std::string, std::string> split_animation(const std::string& path) {
  const size_t hash = path.rfind('#');
  std::error_code ec;
  if (hash == std::string::npos || hash == 0 || std::filesystem::exists(path, ec)) return {path, ""};
  return {path.substr(0, hash), path.substr(hash + 1)};
}

// A file of a registered asset format (not BVH): one a writer can put motion onto.
bool is_asset_file(const std::string& path) { return !is_bvh_file(path) && is_motion_file(path); }

std::vector<Clip> read_whole_file(const std::string& path, const ClipReadOptions& options) {
  const std::string ext = lower_extension(path);
  if (ext == ".bvh") {
    Clip clip = read_bvh(path);
    if (options.fps > 0.0) {
      clip.warnings.push_back(fmt::format("frame rate {:.6g} fps in the file replaced by {:.6g} (--source-fps)",
                                          clip.motion.fps, options.fps));
      clip.motion.fps = options.fps;
    } else if (std::string warning = check_frame_rate(clip).warning; !warning.empty()) {
      clip.warnings.push_back(std::move(warning));
    }
    std::vector<Clip> clips;
    clips.push_back(std::move(clip));
    return clips;
  }
  const ClipFormat* format = format_for(ext);
  if (format == nullptr) {
    std::string known;
    for (const std::string& e : motion_file_extensions()) known += (known.empty() ? "" : " ") + e;
    throw InputError(path, 0, "unknown motion file type '" + ext + "' (nec reads " + known + ")");
  }
  std::vector<Clip> clips = format->read(path, options);
  if (clips.empty()) throw InputError(path, 0, "the file holds no motion");
  return clips;
}

}  // namespace

void register_clip_format(ClipFormat format) {
  std::lock_guard<std::mutex> lock(registry_mutex());
  registry().push_back(std::move(format));
}

void register_clip_writer(ClipWriter writer) {
  std::lock_guard<std::mutex> lock(registry_mutex());
  writers().push_back(std::move(writer));
}

std::vector<std::string> motion_file_extensions() {
  std::vector<std::string> out{".bvh"};
  std::lock_guard<std::mutex> lock(registry_mutex());
  for (const ClipFormat& format : registry()) {
    for (const std::string& ext : format.extensions) {
      if (std::find(out.begin(), out.end(), ext) == out.end()) out.push_back(ext);
    }
  }
  return out;
}

bool is_bvh_file(const std::string& path) { return lower_extension(path) == ".bvh"; }

bool is_motion_file(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".bvh" || format_for(ext) != nullptr;
}

std::vector<Clip> read_clips(const std::string& path, const ClipReadOptions& options) {
  const auto [file, wanted] = split_animation(path);
  if (wanted.empty()) return read_whole_file(path, options);
  std::vector<Clip> clips = read_whole_file(file, options);
  std::string names;
  for (Clip& clip : clips) {
    if (clip.name == wanted) {
      std::vector<Clip> one;
      one.push_back(std::move(clip));
      return one;
    }
    names += (names.empty() ? "'" : ", '") + clip.name + "'";
  }
  throw InputError(file, 0, "no animation named '" + wanted + "' (the file has " + names + ")");
}

Clip read_clip(const std::string& path, const ClipReadOptions& options) {
  std::vector<Clip> clips = read_clips(path, options);
  Clip first = std::move(clips.front());
  if (clips.size() > 1) {
    std::string others;
    for (size_t i = 1; i < clips.size(); ++i) others += (i > 1 ? ", '" : "'") + clips[i].name + "'";
    first.warnings.push_back("the file has " + std::to_string(clips.size()) + " animations; read the first, '" +
                             first.name + "' (others: " + others + "; choose one with FILE#NAME)");
  }
  return first;
}

void check_clip_output(const std::string& out, const std::string& target) {
  const std::string ext = lower_extension(out);
  if (ext == ".bvh") return;
  if (writer_for(ext) == nullptr) {
    std::string known = ".bvh";
    {
      std::lock_guard<std::mutex> lock(registry_mutex());
      for (const ClipWriter& writer : writers()) {
        for (const std::string& e : writer.extensions) known += " " + e;
      }
    }
    throw InputError(out, 0, "nec does not write '" + ext + "' files (it writes " + known + ")");
  }
  if (!is_asset_file(split_animation(target).first)) {
    throw InputError(out, 0, "a '" + ext + "' output is the target's asset with the motion added; the target " +
                                 (target.empty() ? std::string("is missing") : "'" + target + "' is no rigged asset") +
                                 " (write .bvh, or give an FBX / glTF / Collada / .x target)");
  }
}

void write_clip(const std::string& out, const Clip& clip, const std::string& target, const std::string& name) {
  check_clip_output(out, target);
  if (is_bvh_file(out)) {
    write_bvh(out, clip.skeleton, clip.motion);
    return;
  }
  write_file_atomic(out, writer_for(lower_extension(out))->encode(clip, split_animation(target).first, name));
}

std::string encode_clip_onto_asset(const std::string& ext, const Clip& clip, const std::string& target,
                                   const std::string& name) {
  const ClipWriter* writer = writer_for(ext);
  const std::string target_file = split_animation(target).first;
  if (writer == nullptr || !is_asset_file(target_file)) return "";
  return writer->encode(clip, target_file, name);
}

}  // namespace nec
