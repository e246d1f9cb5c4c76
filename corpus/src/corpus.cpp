// Corpus loading: file discovery, reading, captions, segmentation and
// preprocessing, in parallel over files.
#include "nec/corpus/corpus.h"

#include "nec/corpus/take_description.h"

#include "nec/motion/clip_file.h"
#include "nec/motion/error.h"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <thread>

namespace nec {
namespace {

namespace fs = std::filesystem;

std::string extension_list() {
  std::string out;
  for (const std::string& ext : motion_file_extensions()) out += (out.empty() ? "" : " ") + ext;
  return out;
}

std::string folder_name(const fs::path& folder) {
  const fs::path clean = folder.lexically_normal();
  std::string name = clean.filename().string();
  if (name.empty()) name = clean.parent_path().filename().string();
  return name.empty() ? std::string("data") : name;
}

struct FileOutput {
  std::vector<CacheEntry> entries;
  CorpusFileResult result;
};

CacheEntry rejected_entry(const CorpusFile& file, const std::string& reason) {
  CacheEntry entry;
  entry.source = file.path;
  entry.dataset = file.dataset;
  entry.prepared.report.file = file.path;
  entry.prepared.report.rejection = reason;
  return entry;
}

// A described clip's captions: the description's canonical one, the segmenter's, then both sets of paraphrases.
std::vector<std::string> interleave(const std::vector<std::string>& described, const std::vector<std::string>& kinematic) {
  std::vector<std::string> out;
  for (size_t i = 0; i < std::max(described.size(), kinematic.size()); ++i) {
    if (i < described.size()) out.push_back(described[i]);
    if (i < kinematic.size()) out.push_back(kinematic[i]);
  }
  return out;
}

// One take (a BVH file, or one animation of an asset) -> entries, captioned or segmented; a described take
// (description non-null) is segmented and its clips get the description's parts that agree with them.
void load_take(const CorpusFile& file, const Clip& take, const std::string& id, std::vector<std::string> captions,
               const TakeDescription* description, const CorpusOptions& options, FileOutput& out) {
  const bool first_take = out.entries.empty();
  const bool segment = captions.empty() && options.kinematic_captions;
  if (!segment && captions.empty() && description != nullptr) {
    captions = described_clip_captions(*description, Segment{}, options.segment.creature, /*whole_take=*/true);
  }
  if (!segment) {
    CacheEntry entry;
    entry.prepared = preprocess(take, file.path, options.preprocess);
    entry.source = file.path;
    entry.dataset = file.dataset;
    entry.captions = std::move(captions);
    if (id != file.path) entry.id = id;
    if (first_take) out.result.changes = entry.prepared.report.changes;
    if (entry.prepared.report.accepted()) {
      ++out.result.clips;
    } else if (out.result.error.empty()) {
      out.result.error = entry.prepared.report.rejection;
    }
    out.entries.push_back(std::move(entry));
    return;
  }
  const TakeSegmentation cut = segment_take(take, options.segment);
  out.result.segments += static_cast<int>(cut.segments.size());
  for (size_t i = 0; i < cut.segments.size(); ++i) {
    const Segment& s = cut.segments[i];
    Clip piece{take.skeleton, take.motion.slice(s.begin, s.end), take.warnings, take.name};
    CacheEntry entry;
    entry.prepared = preprocess(piece, file.path, options.preprocess);
    entry.source = file.path;
    entry.dataset = file.dataset;
    entry.captions = description == nullptr
                         ? s.captions
                         : interleave(described_clip_captions(*description, s, options.segment.creature,
                                                              cut.segments.size() == 1),
                                      s.captions);
    entry.id = id + "#" + std::to_string(i);
    // The segment's first frame at the corpus frame rate.
    const double fps = entry.prepared.clip.motion.fps;
    entry.source_frame = static_cast<int>(std::lround(s.begin / take.motion.fps * fps));
    if (first_take && i == 0) out.result.changes = entry.prepared.report.changes;
    if (entry.prepared.report.accepted()) ++out.result.clips;
    out.entries.push_back(std::move(entry));
  }
}

FileOutput load_file(const CorpusFile& file, const CorpusOptions& options) {
  FileOutput out;
  out.result.path = file.path;
  out.result.dataset = file.dataset;
  std::vector<Clip> takes;
  std::vector<std::string> captions;
  std::optional<TakeDescription> description;
  try {
    takes = read_clips(file.path, options.read);
    captions = captions_for(file.path, options.captions);
    if (const std::string text = take_description_for(file.path, options.captions); !text.empty()) {
      try {
        description = parse_take_description(text);
      } catch (const std::invalid_argument& e) {
        throw InputError(file.path, 0, e.what());
      }
    }
  } catch (const InputError& e) {
    out.result.error = e.what();
    out.entries.push_back(rejected_entry(file, e.what()));
    return out;
  }
  // A file's captions and description describe its one take; the animations of a file that holds several are
  // segmented.
  for (const Clip& take : takes) {
    const bool several = takes.size() > 1;
    load_take(file, take, several ? file.path + "#" + take.name : file.path,
              several ? std::vector<std::string>{} : captions,
              several || !description ? nullptr : &*description, options, out);
  }
  if (description) ++out.result.described;
  if (out.result.clips == 0 && out.result.error.empty()) out.result.error = "every segment was rejected";
  return out;
}

}  // namespace

std::vector<CorpusFile> find_corpus_files(const std::vector<std::string>& inputs) {
  std::vector<CorpusFile> files;
  for (const std::string& input : inputs) {
    std::string dataset;
    std::string path = input;
    const size_t eq = input.find('=');
    if (eq != std::string::npos && eq > 0 && !fs::exists(input)) {
      dataset = input.substr(0, eq);
      path = input.substr(eq + 1);
    }
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      std::vector<std::string> found;
      for (auto it = fs::recursive_directory_iterator(path, fs::directory_options::follow_directory_symlink, ec);
           !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
        if (it->is_regular_file(ec) && is_motion_file(it->path().string())) found.push_back(it->path().string());
      }
      if (ec) throw InputError(path, 0, "cannot list the folder: " + ec.message());
      if (found.empty()) throw InputError(path, 0, "no motion files in this folder (" + extension_list() + ")");
      std::sort(found.begin(), found.end());
      const std::string name = dataset.empty() ? folder_name(path) : dataset;
      for (std::string& f : found) files.push_back({std::move(f), name});
    } else if (fs::is_regular_file(path, ec)) {
      files.push_back({path, dataset.empty() ? folder_name(fs::path(path).parent_path()) : dataset});
    } else {
      throw InputError(path, 0, "no such file or folder");
    }
  }
  return files;
}

CorpusResult load_corpus(const std::vector<CorpusFile>& files, const CorpusOptions& options) {
  std::vector<FileOutput> outputs(files.size());
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t i = next++; i < files.size(); i = next++) {
      try {
        outputs[i] = load_file(files[i], options);
      } catch (const std::exception& e) {
        outputs[i].result = {files[i].path, files[i].dataset, 0, 0, 0, e.what(), {}};
        outputs[i].entries = {rejected_entry(files[i], e.what())};
      }
    }
  };
  const int threads = std::max(1, options.threads > 0 ? options.threads
                                                      : static_cast<int>(std::thread::hardware_concurrency()));
  std::vector<std::thread> pool;
  for (int t = 1; t < std::min<int>(threads, static_cast<int>(files.size())); ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  CorpusResult result;
  for (FileOutput& out : outputs) {
    for (CacheEntry& e : out.entries) result.entries.push_back(std::move(e));
    result.files.push_back(std::move(out.result));
  }
  return result;
}

}  // namespace nec
