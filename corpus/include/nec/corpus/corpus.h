// Reading a corpus: folders of motion files (BVH, and assets when registered; + captions) -> cache entries.
//
//   CorpusOptions options;                        // preprocessing, captions, segmentation
//   auto files = find_corpus_files({"bandai=../shared/data/bandai", "my_rigs/"});
//   CorpusResult corpus = load_corpus(files, options);
//   write_cache("cache/", corpus.entries, CacheOptions{options.preprocess, split});
//
// Each input is a folder (searched recursively for motion files, motion/clip_file.h) or a file, optionally
// prefixed with `NAME=` to name its dataset; otherwise the dataset is named
// after the folder (or, for a file, its parent folder). Takes without
// captions (the dog) are cut into clips (SegmentOptions: 2–6 s) and captioned
// by the kinematic segmenter; each clip is preprocessed on its own, so it starts at the origin
// facing +Z. A file that cannot be read becomes a rejected entry with the
// reader's message; it never stops the run.
#pragma once

#include "nec/corpus/captions.h"
#include "nec/corpus/dataset.h"
#include "nec/corpus/preprocess.h"
#include "nec/corpus/segment.h"
#include "nec/motion/clip_file.h"

#include <string>
#include <vector>

namespace nec {

struct CorpusFile {
  std::string path;
  std::string dataset;  // e.g. "bandai", "mann_dog"
};

struct CorpusOptions {
  PreprocessOptions preprocess;
  ClipReadOptions read;               // read.fps > 0: every file's true frame rate, replacing what it says
  CaptionSources captions;
  SegmentOptions segment;
  bool kinematic_captions = true;     // cut uncaptioned takes into clips captioned from their kinematics
  int threads = 0;                    // worker threads; 0 = all cores
};

// Expands folders into their motion files (sorted). Throws InputError for an
// input that does not exist or a folder without motion files.
std::vector<CorpusFile> find_corpus_files(const std::vector<std::string>& inputs);

struct CorpusFileResult {
  std::string path;
  std::string dataset;
  int clips = 0;                      // accepted clips made from the file
  int segments = 0;                   // > 0 when the segmenter cut the take
  int described = 0;                  // 1 when a description table described the take
  std::string error;                  // reader error or rejection reason of the whole file
  std::vector<std::string> changes;   // preprocessing report of the first clip
};

struct CorpusResult {
  std::vector<CacheEntry> entries;       // accepted and rejected, in file order
  std::vector<CorpusFileResult> files;   // one per input file, in order
};

CorpusResult load_corpus(const std::vector<CorpusFile>& files, const CorpusOptions& options);

}  // namespace nec
