// The dataset cache on disk: writing (atomic) and reading (checked) the
// manifest.json + features.f32 + skeletons.bin directory described in
// docs/dataset-format.md.
#include "nec/corpus/dataset.h"

#include "dataset_records.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/hash.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

namespace nec {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

constexpr const char* kManifestFile = "manifest.json";
constexpr const char* kFeaturesFile = "features.f32";
constexpr const char* kSkeletonsFile = "skeletons.bin";
constexpr char kSkeletonsMagic[8] = {'N', 'E', 'C', 'S', 'K', 'E', 'L', '\0'};
constexpr size_t kSkeletonsHeaderBytes = 16;  // magic, u32 version, u32 count
constexpr const char* kHint = "; re-run nec prepare to rebuild the cache";

bool host_is_little_endian() {
  const uint16_t probe = 1;
  unsigned char first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

uint32_t byte_swap32(uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0x0000ff00u) | ((v << 8) & 0x00ff0000u) | (v << 24);
}

void swap_float_bytes(float* data, size_t count) {
  for (size_t i = 0; i < count; ++i) {
    uint32_t bits;
    std::memcpy(&bits, data + i, 4);
    bits = byte_swap32(bits);
    std::memcpy(data + i, &bits, 4);
  }
}


// Little-endian serialization of the skeleton records.
class ByteWriter {
 public:
  void u8(uint8_t v) { bytes_.push_back(static_cast<char>(v)); }
  void u32(uint32_t v) {
    for (int i = 0; i < 4; ++i) u8(static_cast<uint8_t>(v >> (8 * i)));
  }
  void i32(int32_t v) { u32(static_cast<uint32_t>(v)); }
  void f64(double v) {
    uint64_t bits;
    std::memcpy(&bits, &v, 8);
    for (int i = 0; i < 8; ++i) u8(static_cast<uint8_t>(bits >> (8 * i)));
  }
  void str(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    bytes_ += s;
  }
  void raw(std::string_view s) { bytes_ += s; }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

// Bounds-checked reading; a short read throws InputError naming the file.
class ByteReader {
 public:
  ByteReader(std::string_view data, std::string file) : data_(data), file_(std::move(file)) {}
  uint8_t u8() {
    need(1);
    return static_cast<uint8_t>(data_[position_++]);
  }
  uint32_t u32() {
    need(4);
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(static_cast<uint8_t>(data_[position_ + i])) << (8 * i);
    position_ += 4;
    return v;
  }
  int32_t i32() { return static_cast<int32_t>(u32()); }
  double f64() {
    need(8);
    uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) bits |= static_cast<uint64_t>(static_cast<uint8_t>(data_[position_ + i])) << (8 * i);
    position_ += 8;
    double v;
    std::memcpy(&v, &bits, 8);
    return v;
  }
  std::string str() {
    const uint32_t size = u32();
    need(size);
    std::string s(data_.substr(position_, size));
    position_ += size;
    return s;
  }
  std::string_view raw(size_t size) {
    need(size);
    const std::string_view s = data_.substr(position_, size);
    position_ += size;
    return s;
  }
  size_t position() const { return position_; }

 private:
  void need(size_t size) const {
    if (size > data_.size() - position_) {
      throw InputError(file_, 0,
                       "truncated: " + std::to_string(size) + " more bytes needed at byte " + std::to_string(position_) +
                           " of a " + std::to_string(data_.size()) + "-byte record" + kHint);
    }
  }

  std::string_view data_;
  std::string file_;
  size_t position_ = 0;
};


}  // namespace

namespace detail {

std::string hex16(uint64_t value) {
  static const char* digits = "0123456789abcdef";
  std::string out(16, '0');
  for (int i = 15; i >= 0; --i) {
    out[i] = digits[value & 0xf];
    value >>= 4;
  }
  return out;
}

// One skeleton record of skeletons.bin (see docs/dataset-format.md).
std::string serialize_skeleton(const Skeleton& s, const std::vector<std::string>& canonical_names) {
  ByteWriter w;
  w.u32(static_cast<uint32_t>(s.joint_count()));
  for (int j = 0; j < s.joint_count(); ++j) {
    w.str(s.names[j]);
    w.str(canonical_names[j]);
    w.i32(s.parents[j]);
    for (int k = 0; k < 3; ++k) w.f64(s.offsets[j][k]);
    const ChannelLayout& layout = s.channels[j];
    w.u8(static_cast<uint8_t>(layout.count));
    for (int c = 0; c < layout.count; ++c) w.u8(static_cast<uint8_t>(layout.channels[c]));
  }
  w.u32(static_cast<uint32_t>(s.end_sites.size()));
  for (const EndSite& site : s.end_sites) {
    w.i32(site.parent);
    for (int k = 0; k < 3; ++k) w.f64(site.offset[k]);
  }
  return w.bytes();
}

}  // namespace detail

namespace {

using detail::hex16;
using detail::serialize_skeleton;

CachedSkeleton parse_skeleton(std::string_view record, const std::string& file, int index) {
  const std::string what = "skeleton " + std::to_string(index) + ": ";
  ByteReader r(record, file);
  CachedSkeleton out;
  Skeleton& s = out.skeleton;
  const uint32_t joints = r.u32();
  // Each joint takes at least 4 + 4 + 4 + 24 + 1 bytes: reject absurd counts before allocating.
  if (joints == 0 || joints > record.size() / 37) {
    throw InputError(file, 0, what + "bad joint count " + std::to_string(joints) + kHint);
  }
  for (uint32_t j = 0; j < joints; ++j) {
    std::string name = r.str();
    out.canonical_names.push_back(r.str());
    const int parent = r.i32();
    Vec3 offset;
    for (int k = 0; k < 3; ++k) offset[k] = r.f64();
    ChannelLayout layout;
    const uint8_t count = r.u8();
    if (count > 6) throw InputError(file, 0, what + "joint " + std::to_string(j) + " has " + std::to_string(count) + " channels" + kHint);
    for (int c = 0; c < count; ++c) {
      const uint8_t channel = r.u8();
      if (channel > static_cast<uint8_t>(Channel::Zrotation)) {
        throw InputError(file, 0, what + "unknown channel code " + std::to_string(channel) + kHint);
      }
      layout.push(static_cast<Channel>(channel));
    }
    if (parent < -1 || parent >= static_cast<int>(j)) {
      throw InputError(file, 0, what + "joint " + std::to_string(j) + " has parent " + std::to_string(parent) + kHint);
    }
    s.add_joint(std::move(name), parent, offset, layout);
  }
  const uint32_t sites = r.u32();
  if (sites > record.size() / 28) throw InputError(file, 0, what + "bad end site count" + kHint);
  for (uint32_t i = 0; i < sites; ++i) {
    EndSite site;
    site.parent = r.i32();
    for (int k = 0; k < 3; ++k) site.offset[k] = r.f64();
    if (site.parent < 0 || site.parent >= static_cast<int>(joints)) {
      throw InputError(file, 0, what + "end site on joint " + std::to_string(site.parent) + kHint);
    }
    s.end_sites.push_back(site);
  }
  if (r.position() != record.size()) {
    throw InputError(file, 0, what + std::to_string(record.size() - r.position()) + " unexpected trailing bytes" + kHint);
  }
  try {
    s.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(file, 0, what + e.what() + kHint);
  }
  return out;
}

std::string up_axis_name(UpAxis up) {
  switch (up) {
    case UpAxis::Y: return "y";
    case UpAxis::Z: return "z";
    case UpAxis::Auto: break;
  }
  return "auto";
}

UpAxis parse_up_axis(const std::string& name, const std::string& file) {
  if (name == "auto") return UpAxis::Auto;
  if (name == "y") return UpAxis::Y;
  if (name == "z") return UpAxis::Z;
  throw InputError(file, 0, "unknown up axis '" + name + "'" + kHint);
}

Json options_to_json(const CacheOptions& options) {
  const PreprocessOptions& p = options.preprocess;
  const SplitOptions& s = options.split;
  Json out;
  out["preprocess"] = {{"target_fps", p.target_fps},
                       {"max_bone_ratio", p.max_bone_ratio},
                       {"translation_tolerance", p.translation_tolerance},
                       {"translation_bone_tolerance", p.translation_bone_tolerance},
                       {"fold_any_translation", p.fold_any_translation},
                       {"up", up_axis_name(p.up)},
                       {"min_frames", p.min_frames},
                       {"canonical_rest", p.canonical_rest}};
  out["split"] = {{"val_fraction", s.val_fraction},
                  {"test_fraction", s.test_fraction},
                  {"seed", s.seed},
                  {"held_out_skeletons", s.held_out_skeletons},
                  {"held_out_datasets", s.held_out_datasets}};
  return out;
}

CacheOptions options_from_json(const Json& j, const std::string& file) {
  CacheOptions options;
  const Json& p = j.at("preprocess");
  options.preprocess.target_fps = p.at("target_fps").get<double>();
  options.preprocess.max_bone_ratio = p.at("max_bone_ratio").get<double>();
  options.preprocess.translation_tolerance = p.at("translation_tolerance").get<double>();
  // Caches written before these limits existed folded by the diameter alone.
  options.preprocess.translation_bone_tolerance = p.value("translation_bone_tolerance", std::numeric_limits<double>::max());
  options.preprocess.fold_any_translation = p.value("fold_any_translation", false);
  options.preprocess.up = parse_up_axis(p.at("up").get<std::string>(), file);
  options.preprocess.min_frames = p.at("min_frames").get<int>();
  options.preprocess.canonical_rest = p.at("canonical_rest").get<bool>();
  const Json& s = j.at("split");
  options.split.val_fraction = s.at("val_fraction").get<double>();
  options.split.test_fraction = s.at("test_fraction").get<double>();
  options.split.seed = s.at("seed").get<uint64_t>();
  options.split.held_out_skeletons = s.at("held_out_skeletons").get<std::vector<std::string>>();
  options.split.held_out_datasets = s.at("held_out_datasets").get<std::vector<std::string>>();
  return options;
}

// A clip's rest frames as stored: one flat list (w, x, y, z per joint) per distinct set, clips of one rig sharing one.
std::string rest_frames_key(const std::vector<Quat>& frames) {
  return std::string(reinterpret_cast<const char*>(frames.data()), frames.size() * sizeof(Quat));
}

Json rest_frames_to_json(const std::vector<Quat>& frames) {
  Json out = Json::array();
  for (const Quat& q : frames) {
    for (double v : {q.w(), q.x(), q.y(), q.z()}) out.push_back(v);
  }
  return out;
}

std::vector<Quat> rest_frames_from_json(const Json& j, const std::string& file, size_t index) {
  const auto values = j.get<std::vector<double>>();
  if (values.size() % 4 != 0) {
    throw InputError(file, 0, "rest_frames " + std::to_string(index) + " is not a list of quaternions" + kHint);
  }
  std::vector<Quat> frames;
  for (size_t i = 0; i < values.size(); i += 4) frames.emplace_back(values[i], values[i + 1], values[i + 2], values[i + 3]);
  return frames;
}

Json clip_to_json(const CacheClip& c, size_t feature_offset, int rest_frames) {
  const Normalization& n = c.normalization;
  Json out;
  out["id"] = c.id;
  out["source"] = c.source;
  out["dataset"] = c.dataset;
  out["skeleton"] = c.skeleton;
  out["frames"] = c.frame_count;
  out["joints"] = c.joint_count;
  out["fps"] = c.fps;
  out["source_frame"] = c.source_frame;
  out["feature_offset"] = feature_offset;
  out["start_xz"] = {c.start_xz[0], c.start_xz[1]};
  out["captions"] = c.captions;
  out["split"] = std::string(split_name(c.split));
  out["normalization"] = {{"scale", n.scale},
                          {"rotation", {n.rotation.w(), n.rotation.x(), n.rotation.y(), n.rotation.z()}},
                          {"origin", {n.origin.x(), n.origin.y(), n.origin.z()}},
                          {"source_fps", n.source_fps},
                          {"rest_frames", rest_frames}};
  out["report"] = c.report;
  return out;
}

CacheClip clip_from_json(const Json& j, const std::string& file, int index,
                         const std::vector<std::vector<Quat>>& rest_frames) {
  CacheClip c;
  c.id = j.at("id").get<std::string>();
  c.source = j.at("source").get<std::string>();
  c.dataset = j.at("dataset").get<std::string>();
  c.skeleton = j.at("skeleton").get<int>();
  c.frame_count = j.at("frames").get<int>();
  c.joint_count = j.at("joints").get<int>();
  c.fps = j.at("fps").get<double>();
  c.source_frame = j.at("source_frame").get<int>();
  c.feature_offset = j.at("feature_offset").get<size_t>();
  const auto start = j.at("start_xz").get<std::vector<double>>();
  c.captions = j.at("captions").get<std::vector<std::string>>();
  const std::string split = j.at("split").get<std::string>();
  const std::optional<Split> parsed = parse_split(split);
  const std::string what = "clip " + std::to_string(index) + " ('" + c.id + "'): ";
  if (!parsed) throw InputError(file, 0, what + "unknown split '" + split + "'" + kHint);
  c.split = *parsed;
  const Json& n = j.at("normalization");
  c.normalization.scale = n.at("scale").get<double>();
  const auto rotation = n.at("rotation").get<std::vector<double>>();
  const auto origin = n.at("origin").get<std::vector<double>>();
  c.normalization.source_fps = n.at("source_fps").get<double>();
  const int rest = n.at("rest_frames").get<int>();
  c.report = j.at("report").get<std::vector<std::string>>();
  if (start.size() != 2 || rotation.size() != 4 || origin.size() != 3) {
    throw InputError(file, 0, what + "start_xz needs 2 numbers, rotation 4 and origin 3" + kHint);
  }
  c.start_xz = {start[0], start[1]};
  c.normalization.rotation = Quat(rotation[0], rotation[1], rotation[2], rotation[3]);
  c.normalization.origin = Vec3(origin[0], origin[1], origin[2]);
  if (rest < -1 || rest >= static_cast<int>(rest_frames.size())) {
    throw InputError(file, 0, what + "unknown rest_frames " + std::to_string(rest) + kHint);
  }
  if (rest >= 0) {
    c.normalization.rest_frames = rest_frames[rest];
    if (static_cast<int>(c.normalization.rest_frames.size()) != c.joint_count) {
      throw InputError(file, 0, what + "rest_frames " + std::to_string(rest) + " has " +
                                    std::to_string(c.normalization.rest_frames.size()) + " joints, the clip " +
                                    std::to_string(c.joint_count) + kHint);
    }
  }
  if (c.frame_count < 1) throw InputError(file, 0, what + "has " + std::to_string(c.frame_count) + " frames" + kHint);
  return c;
}

void write_binary(const fs::path& path, const char* data, size_t size, std::ofstream& out) {
  out.write(data, static_cast<std::streamsize>(size));
  if (!out) throw std::runtime_error(path.string() + ": write failed: " + std::strerror(errno));
}

void write_features(const DatasetCache& cache, const fs::path& path, std::vector<size_t>& offsets) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path.string() + ": cannot write: " + std::strerror(errno));
  const bool swap = !host_is_little_endian();
  std::vector<float> buffer;
  size_t written = 0;
  for (const CacheClip& c : cache.clips) {
    const size_t size = c.feature_size();
    if (c.feature_offset + size > cache.feature_data.size()) {
      throw std::invalid_argument("save_cache: clip '" + c.id + "' lies outside feature_data");
    }
    const float* data = cache.feature_data.data() + c.feature_offset;
    if (swap) {
      buffer.assign(data, data + size);
      swap_float_bytes(buffer.data(), size);
      data = buffer.data();
    }
    write_binary(path, reinterpret_cast<const char*>(data), size * sizeof(float), out);
    offsets.push_back(written);
    written += size;
  }
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": write failed: " + std::strerror(errno));
}

std::string random_suffix() {
  std::random_device entropy;
  return hex16((static_cast<uint64_t>(entropy()) << 32) ^ entropy());
}

// The directory the cache goes to, without a trailing separator.
fs::path cache_path(const std::string& dir) {
  fs::path target = fs::path(dir).lexically_normal();
  if (target.filename().empty()) target = target.parent_path();
  if (target.empty()) throw InputError(dir, 0, "not a usable cache directory name");
  return target;
}

}  // namespace

FeatureArray FeatureArray::map_file(const std::string& path, size_t floats) {
  FeatureArray out;
  if (floats == 0) return out;
  const size_t bytes = floats * sizeof(float);
  if (!host_is_little_endian()) {
    std::vector<float> values(floats);
    std::ifstream in(path, std::ios::binary);
    in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(bytes));
    if (!in) throw InputError(path, 0, std::string("read failed: ") + std::strerror(errno) + kHint);
    swap_float_bytes(values.data(), floats);
    return FeatureArray(std::move(values));
  }
  MappedFile file;
  try {
    file = MappedFile::open(path, /*populate=*/true);
  } catch (const InputError& e) {
    throw InputError(e.what() + std::string(kHint));
  }
  if (file.size() < bytes) {
    throw InputError(path, 0, std::to_string(file.size()) + " bytes, expected " + std::to_string(bytes) + kHint);
  }
  const float* mapping = reinterpret_cast<const float*>(file.data());
  out.owner_ = std::make_shared<MappedFile>(std::move(file));
  out.data_ = mapping;
  out.size_ = floats;
  return out;
}

void save_cache(const DatasetCache& cache, const std::string& dir) {
  const fs::path target = cache_path(dir);
  std::error_code ec;
  if (fs::exists(target, ec)) {
    if (!fs::is_directory(target, ec)) throw InputError(dir, 0, "exists and is not a directory");
    if (!fs::is_empty(target, ec) && !fs::exists(target / kManifestFile, ec)) {
      throw InputError(dir, 0, "exists and is not a dataset cache (no manifest.json); refusing to replace it");
    }
  }
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  fs::create_directories(parent, ec);
  if (ec) throw std::runtime_error(parent.string() + ": cannot create the directory: " + ec.message());
  const std::string name = target.filename().string();
  const fs::path temp = parent / ("." + name + ".tmp-" + random_suffix());
  fs::create_directory(temp, ec);
  if (ec) throw std::runtime_error(temp.string() + ": cannot create the directory: " + ec.message());

  fs::path old;
  try {
    std::vector<size_t> feature_offsets;
    write_features(cache, temp / kFeaturesFile, feature_offsets);

    Json manifest;
    manifest["format"] = kDatasetFormatName;
    manifest["version"] = kDatasetFormatVersion;
    manifest["fps"] = cache.fps;
    manifest["options"] = options_to_json(cache.options);

    ByteWriter skeleton_file;
    skeleton_file.raw(std::string_view(kSkeletonsMagic, sizeof(kSkeletonsMagic)));
    skeleton_file.u32(static_cast<uint32_t>(kDatasetFormatVersion));
    skeleton_file.u32(static_cast<uint32_t>(cache.skeletons.size()));
    Json skeletons = Json::array();
    for (size_t s = 0; s < cache.skeletons.size(); ++s) {
      const CachedSkeleton& stored = cache.skeletons[s];
      if (stored.canonical_names.size() != stored.skeleton.names.size()) {
        throw std::invalid_argument("save_cache: skeleton '" + stored.name + "' needs one canonical name per joint");
      }
      const std::string record = serialize_skeleton(stored.skeleton, stored.canonical_names);
      skeletons.push_back({{"index", s},
                           {"name", stored.name},
                           {"hash", hex16(fnv1a64(record))},
                           {"joints", stored.skeleton.joint_count()},
                           {"byte_offset", skeleton_file.bytes().size()},
                           {"byte_size", record.size()}});
      skeleton_file.raw(record);
    }
    {
      std::ofstream out(temp / kSkeletonsFile, std::ios::binary | std::ios::trunc);
      write_binary(temp / kSkeletonsFile, skeleton_file.bytes().data(), skeleton_file.bytes().size(), out);
      out.close();
      if (!out) throw std::runtime_error((temp / kSkeletonsFile).string() + ": write failed");
    }

    const size_t floats = feature_offsets.empty() ? 0 : feature_offsets.back() + cache.clips.back().feature_size();
    manifest["files"] = {{"features", {{"name", kFeaturesFile}, {"dtype", "float32"}, {"byte_order", "little"},
                                       {"floats", floats}, {"bytes", floats * sizeof(float)}}},
                         {"skeletons", {{"name", kSkeletonsFile}, {"bytes", skeleton_file.bytes().size()}}}};
    manifest["skeletons"] = std::move(skeletons);
    Json clips = Json::array();
    Json rest_frames = Json::array();
    std::unordered_map<std::string, int> rest_frames_index;
    for (size_t i = 0; i < cache.clips.size(); ++i) {
      const CacheClip& c = cache.clips[i];
      if (c.skeleton < 0 || c.skeleton >= static_cast<int>(cache.skeletons.size()) ||
          c.joint_count != cache.skeletons[c.skeleton].skeleton.joint_count()) {
        throw std::invalid_argument("save_cache: clip '" + c.id + "' does not match its skeleton");
      }
      int rest = -1;
      if (!c.normalization.rest_frames.empty()) {
        const auto [it, added] =
            rest_frames_index.emplace(rest_frames_key(c.normalization.rest_frames), static_cast<int>(rest_frames.size()));
        if (added) rest_frames.push_back(rest_frames_to_json(c.normalization.rest_frames));
        rest = it->second;
      }
      clips.push_back(clip_to_json(c, feature_offsets[i], rest));
    }
    manifest["rest_frames"] = std::move(rest_frames);
    manifest["clips"] = std::move(clips);
    Json rejected = Json::array();
    for (const RejectedFile& r : cache.rejected) {
      rejected.push_back({{"source", r.source}, {"dataset", r.dataset}, {"reason", r.reason}, {"report", r.report}});
    }
    manifest["rejected"] = std::move(rejected);
    write_file_atomic((temp / kManifestFile).string(), manifest.dump(1) + "\n");

    if (fs::exists(target, ec)) {
      old = parent / ("." + name + ".old-" + random_suffix());
      fs::rename(target, old);
    }
    fs::rename(temp, target);
  } catch (...) {
    remove_tree(temp.string());
    std::error_code ignored;
    if (!old.empty() && !fs::exists(target, ignored)) fs::rename(old, target, ignored);
    throw;
  }
  if (!old.empty()) remove_tree(old.string());
}

void write_cache(const std::string& dir, const std::vector<CacheEntry>& entries, const CacheOptions& options) {
  save_cache(build_cache(entries, options), dir);
}

DatasetCache read_cache(const std::string& dir) {
  const fs::path root = cache_path(dir);
  const std::string manifest_path = (root / kManifestFile).string();
  const std::string features_path = (root / kFeaturesFile).string();
  const std::string skeletons_path = (root / kSkeletonsFile).string();
  std::error_code ec;
  if (!fs::is_directory(root, ec)) throw InputError(dir, 0, "no such directory (make a dataset cache with nec prepare)");
  if (!fs::exists(manifest_path, ec)) {
    throw InputError(dir, 0, "no manifest.json: not a dataset cache (make one with nec prepare)");
  }

  Json manifest;
  try {
    manifest = Json::parse(read_file(manifest_path));
  } catch (const Json::exception& e) {
    throw InputError(manifest_path, 0, std::string("not valid JSON: ") + e.what() + kHint);
  }

  DatasetCache cache;
  cache.directory = root.string();
  std::vector<std::pair<size_t, size_t>> skeleton_ranges;  // (byte offset, byte size) in skeletons.bin
  std::vector<std::string> skeleton_hashes;
  size_t feature_floats = 0;
  size_t skeleton_bytes = 0;
  try {
    if (!manifest.is_object() || manifest.value("format", std::string()) != kDatasetFormatName) {
      throw InputError(manifest_path, 0, std::string("not a dataset manifest (format is not '") + kDatasetFormatName + "')" + kHint);
    }
    const int version = manifest.at("version").get<int>();
    if (version != kDatasetFormatVersion) {
      throw InputError(manifest_path, 0,
                       "format version " + std::to_string(version) + ", this build reads version " +
                           std::to_string(kDatasetFormatVersion) + kHint);
    }
    cache.fps = manifest.at("fps").get<double>();
    cache.options = options_from_json(manifest.at("options"), manifest_path);
    const Json& files = manifest.at("files");
    feature_floats = files.at("features").at("floats").get<size_t>();
    skeleton_bytes = files.at("skeletons").at("bytes").get<size_t>();
    for (const Json& s : manifest.at("skeletons")) {
      CachedSkeleton stored;
      stored.name = s.at("name").get<std::string>();
      stored.hash = s.at("hash").get<std::string>();
      skeleton_hashes.push_back(stored.hash);
      skeleton_ranges.emplace_back(s.at("byte_offset").get<size_t>(), s.at("byte_size").get<size_t>());
      cache.skeletons.push_back(std::move(stored));
    }
    std::vector<std::vector<Quat>> rest_frames;
    for (const Json& r : manifest.at("rest_frames")) {
      rest_frames.push_back(rest_frames_from_json(r, manifest_path, rest_frames.size()));
    }
    const Json& clips = manifest.at("clips");
    cache.clips.reserve(clips.size());
    for (const Json& c : clips) {
      cache.clips.push_back(clip_from_json(c, manifest_path, static_cast<int>(cache.clips.size()), rest_frames));
    }
    for (const Json& r : manifest.at("rejected")) {
      cache.rejected.push_back({r.at("source").get<std::string>(), r.at("dataset").get<std::string>(),
                                r.at("reason").get<std::string>(), r.at("report").get<std::vector<std::string>>()});
    }
  } catch (const Json::exception& e) {
    throw InputError(manifest_path, 0, std::string("malformed manifest: ") + e.what() + kHint);
  }

  // Skeletons.
  const std::string skeleton_data = read_file(skeletons_path);
  if (skeleton_data.size() != skeleton_bytes) {
    throw InputError(skeletons_path, 0,
                     std::to_string(skeleton_data.size()) + " bytes, the manifest expects " +
                         std::to_string(skeleton_bytes) + kHint);
  }
  {
    ByteReader header(skeleton_data, skeletons_path);
    if (header.raw(sizeof(kSkeletonsMagic)) != std::string_view(kSkeletonsMagic, sizeof(kSkeletonsMagic))) {
      throw InputError(skeletons_path, 0, "not a skeleton file (bad magic)" + std::string(kHint));
    }
    const uint32_t version = header.u32();
    const uint32_t count = header.u32();
    if (version != static_cast<uint32_t>(kDatasetFormatVersion)) {
      throw InputError(skeletons_path, 0, "format version " + std::to_string(version) + ", this build reads version " +
                                              std::to_string(kDatasetFormatVersion) + kHint);
    }
    if (count != cache.skeletons.size()) {
      throw InputError(skeletons_path, 0, "holds " + std::to_string(count) + " skeletons, the manifest lists " +
                                              std::to_string(cache.skeletons.size()) + kHint);
    }
  }
  for (size_t s = 0; s < cache.skeletons.size(); ++s) {
    const auto [offset, size] = skeleton_ranges[s];
    if (offset < kSkeletonsHeaderBytes || offset > skeleton_data.size() || size > skeleton_data.size() - offset) {
      throw InputError(skeletons_path, 0, "skeleton " + std::to_string(s) + " lies outside the file" + kHint);
    }
    const std::string_view record(skeleton_data.data() + offset, size);
    if (hex16(fnv1a64(record)) != skeleton_hashes[s]) {
      throw InputError(skeletons_path, 0, "skeleton " + std::to_string(s) + " does not match its hash in the manifest" + kHint);
    }
    CachedSkeleton parsed = parse_skeleton(record, skeletons_path, static_cast<int>(s));
    cache.skeletons[s].skeleton = std::move(parsed.skeleton);
    cache.skeletons[s].canonical_names = std::move(parsed.canonical_names);
  }

  // Clips against skeletons and the feature array.
  size_t expected_offset = 0;
  for (size_t i = 0; i < cache.clips.size(); ++i) {
    const CacheClip& c = cache.clips[i];
    const std::string what = "clip " + std::to_string(i) + " ('" + c.id + "'): ";
    if (c.skeleton < 0 || c.skeleton >= static_cast<int>(cache.skeletons.size())) {
      throw InputError(manifest_path, 0, what + "unknown skeleton " + std::to_string(c.skeleton) + kHint);
    }
    if (c.joint_count != cache.skeletons[c.skeleton].skeleton.joint_count()) {
      throw InputError(manifest_path, 0, what + std::to_string(c.joint_count) + " joints, its skeleton has " +
                                             std::to_string(cache.skeletons[c.skeleton].skeleton.joint_count()) + kHint);
    }
    if (c.feature_offset != expected_offset) {
      throw InputError(manifest_path, 0, what + "features at float " + std::to_string(c.feature_offset) + ", expected " +
                                             std::to_string(expected_offset) + kHint);
    }
    expected_offset += c.feature_size();
  }
  if (expected_offset != feature_floats) {
    throw InputError(manifest_path, 0, "clips hold " + std::to_string(expected_offset) + " floats, files.features lists " +
                                           std::to_string(feature_floats) + kHint);
  }

  const uintmax_t feature_bytes = fs::file_size(features_path, ec);
  if (ec) throw InputError(features_path, 0, "cannot read: " + ec.message() + kHint);
  if (feature_bytes != feature_floats * sizeof(float)) {
    throw InputError(features_path, 0, std::to_string(feature_bytes) + " bytes, the manifest expects " +
                                           std::to_string(feature_floats * sizeof(float)) +
                                           " (truncated or from another cache)" + kHint);
  }
  cache.feature_data = FeatureArray::map_file(features_path, feature_floats);
  return cache;
}

uint64_t cache_key(const DatasetCache& cache) {
  uint64_t key = kFnv1aOffset;
  if (!cache.directory.empty()) {
    key = fnv1a64(read_file((fs::path(cache.directory) / "manifest.json").string(), size_t{1} << 30));
  }
  const uint64_t clips = static_cast<uint64_t>(cache.clip_count());
  return fnv1a64(std::string_view(reinterpret_cast<const char*>(&clips), sizeof clips), key);
}

}  // namespace nec
