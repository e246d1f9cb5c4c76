// Corpus loading: file discovery, reading, captions, segmentation and
// preprocessing, in parallel over files.
#include "nec/motion/corpus.h"

#include "nec/motion/bvh.h"
#include "nec/motion/error.h"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <thread>

namespace nec {
namespace {

namespace fs = std::filesystem;

bool is_bvh(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".bvh";
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

FileOutput load_file(const CorpusFile& file, const CorpusOptions& options) {
  FileOutput out;
  out.result.path = file.path;
  out.result.dataset = file.dataset;
  Clip take;
  std::vector<std::string> captions;
  try {
    take = read_bvh(file.path);
    captions = captions_for(file.path, options.captions);
  } catch (const InputError& e) {
    out.result.error = e.what();
    out.entries.push_back(rejected_entry(file, e.what()));
    return out;
  }
  const bool segment = captions.empty() && options.kinematic_captions;
  if (!segment) {
    CacheEntry entry;
    entry.prepared = preprocess(take, file.path, options.preprocess);
    entry.source = file.path;
    entry.dataset = file.dataset;
    entry.captions = std::move(captions);
    out.result.changes = entry.prepared.report.changes;
    if (entry.prepared.report.accepted()) {
      out.result.clips = 1;
    } else {
      out.result.error = entry.prepared.report.rejection;
    }
    out.entries.push_back(std::move(entry));
    return out;
  }
  const TakeSegmentation cut = segment_take(take, options.segment);
  out.result.segments = static_cast<int>(cut.segments.size());
  for (size_t i = 0; i < cut.segments.size(); ++i) {
    const Segment& s = cut.segments[i];
    Clip piece{take.skeleton, take.motion.slice(s.begin, s.end), take.warnings};
    CacheEntry entry;
    entry.prepared = preprocess(piece, file.path, options.preprocess);
    entry.source = file.path;
    entry.dataset = file.dataset;
    entry.captions = s.captions;
    entry.id = file.path + "#" + std::to_string(i);
    // The segment's first frame at the corpus frame rate.
    const double fps = entry.prepared.clip.motion.fps;
    entry.source_frame = static_cast<int>(std::lround(s.begin / take.motion.fps * fps));
    if (i == 0) out.result.changes = entry.prepared.report.changes;
    if (entry.prepared.report.accepted()) ++out.result.clips;
    out.entries.push_back(std::move(entry));
  }
  if (out.result.clips == 0) out.result.error = "every segment was rejected";
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
        if (it->is_regular_file(ec) && is_bvh(it->path())) found.push_back(it->path().string());
      }
      if (ec) throw InputError(path, 0, "cannot list the folder: " + ec.message());
      if (found.empty()) throw InputError(path, 0, "no .bvh files in this folder");
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
        outputs[i].result = {files[i].path, files[i].dataset, 0, 0, e.what(), {}};
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
