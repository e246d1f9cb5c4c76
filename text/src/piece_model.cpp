// The sentencepiece bridge, opened with dlopen (piece_model.h, spm/bridge.h).
#include "nec/text/piece_model.h"

#include "../spm/bridge.h"

#include "nec/text/caption_text.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <dlfcn.h>
#include <unistd.h>

#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <system_error>

namespace nec::text {
namespace {

namespace fs = std::filesystem;

constexpr size_t kErrorSize = 1024;
constexpr const char* kWordStart = "\xE2\x96\x81";  // U+2581, sentencepiece's word-start mark

// The bridge's functions, looked up once per process.
struct Bridge {
  int (*abi)();
  int (*train)(const char*, char*, size_t);
  nec_spm_model* (*load)(const char*, char*, size_t);
  void (*free)(nec_spm_model*);
  int (*vocab_size)(const nec_spm_model*);
  int (*pad_id)(const nec_spm_model*);
  int (*unk_id)(const nec_spm_model*);
  int (*encode)(const nec_spm_model*, const char*, int32_t*, int, char*, size_t);
  int (*decode)(const nec_spm_model*, const int32_t*, int, char*, size_t, char*, size_t);
  int (*piece)(const nec_spm_model*, int, char*, size_t);
};

// $NEC_SPM_BRIDGE, else the library beside the build's text/ folder of the
// running program (build/apps/nec, build/tests/test_x), else the path it was built at.
std::vector<std::string> bridge_candidates() {
  std::vector<std::string> out;
  if (const char* env = std::getenv("NEC_SPM_BRIDGE"); env != nullptr && *env != '\0') return {env};
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  if (!error) out.push_back((exe.parent_path().parent_path() / "text" / fs::path(NEC_SPM_BRIDGE_PATH).filename()).string());
  out.push_back(NEC_SPM_BRIDGE_PATH);
  return out;
}

template <typename F>
void bind(void* library, const char* name, F& function, const std::string& path) {
  void* symbol = dlsym(library, name);
  if (symbol == nullptr) throw std::runtime_error(path + ": the sentencepiece bridge lacks " + name + "; rebuild nec");
  function = reinterpret_cast<F>(symbol);
}

const Bridge& bridge() {
  static std::once_flag once;
  static Bridge functions;
  std::call_once(once, [] {
    std::string tried;
    void* library = nullptr;
    std::string path;
    for (const std::string& candidate : bridge_candidates()) {
      if (!fs::exists(candidate)) {
        tried += (tried.empty() ? "" : ", ") + candidate + " (missing)";
        continue;
      }
      // RTLD_DEEPBIND: sentencepiece and its bundled protobuf resolve their own
      // symbols before the process's (libtorch's protobuf); RTLD_LOCAL keeps them out of it.
      library = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
      if (library != nullptr) {
        path = candidate;
        break;
      }
      tried += (tried.empty() ? "" : ", ") + candidate + " (" + dlerror() + ")";
    }
    if (library == nullptr) {
      throw std::runtime_error("cannot open the sentencepiece bridge: tried " + tried +
                               "; build nec (scripts/setup.sh) or set NEC_SPM_BRIDGE");
    }
    bind(library, "nec_spm_abi", functions.abi, path);
    if (functions.abi() != NEC_SPM_BRIDGE_ABI) {
      throw std::runtime_error(path + " is another version of the sentencepiece bridge; rebuild nec");
    }
    bind(library, "nec_spm_train", functions.train, path);
    bind(library, "nec_spm_load", functions.load, path);
    bind(library, "nec_spm_free", functions.free, path);
    bind(library, "nec_spm_vocab_size", functions.vocab_size, path);
    bind(library, "nec_spm_pad_id", functions.pad_id, path);
    bind(library, "nec_spm_unk_id", functions.unk_id, path);
    bind(library, "nec_spm_encode", functions.encode, path);
    bind(library, "nec_spm_decode", functions.decode, path);
    bind(library, "nec_spm_piece", functions.piece, path);
  });
  return functions;
}

// A fresh directory under the system's temporary folder, removed when done.
class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (fs::temp_directory_path() / "nec-spm-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot make a temporary folder in " + pattern);
    path_ = pattern;
  }
  ~TempFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

}  // namespace

void PieceTrainOptions::validate() const {
  if (vocab_size < 8 || vocab_size > 1000000) {
    throw std::invalid_argument("vocab_size must be in [8, 1000000], got " + std::to_string(vocab_size));
  }
  if (model_type != "unigram" && model_type != "bpe" && model_type != "word" && model_type != "char") {
    throw std::invalid_argument("model_type must be unigram, bpe, word or char, got '" + model_type + "'");
  }
  if (threads < 1) throw std::invalid_argument("threads must be >= 1");
}

void train_piece_model(const std::vector<std::string>& sentences, const PieceTrainOptions& options,
                       const std::string& out_path) {
  options.validate();
  std::string text;
  for (const std::string& sentence : sentences) {
    if (sentence.find_first_of("\n\r") != std::string::npos) {
      throw std::invalid_argument("train_piece_model: a sentence holds a line break: '" + sentence + "'");
    }
    if (!sentence.empty()) text += sentence + "\n";
  }
  if (text.empty()) throw InputError(out_path, 0, "no captions to train the piece model on");
  const Bridge& spm = bridge();
  const TempFolder temp;
  if (temp.path().string().find(' ') != std::string::npos) {
    throw std::runtime_error("the temporary folder " + temp.path().string() + " has a space in its path; set TMPDIR");
  }
  const fs::path input = temp.path() / "captions.txt";
  write_file_atomic(input.string(), text);
  // Our own normalization ran already (caption_text.h): sentencepiece's stays off.
  const std::string args = "--input=" + input.string() + " --model_prefix=" + (temp.path() / "spm").string() +
                           " --vocab_size=" + std::to_string(options.vocab_size) + " --model_type=" + options.model_type +
                           " --hard_vocab_limit=false --character_coverage=1.0 --normalization_rule_name=identity" +
                           " --pad_id=0 --unk_id=1 --bos_id=-1 --eos_id=-1 --num_threads=" + std::to_string(options.threads) +
                           " --minloglevel=2";
  char error[kErrorSize] = {0};
  if (spm.train(args.c_str(), error, sizeof error) != 0) {
    throw InputError(out_path, 0, std::string("sentencepiece could not train on the captions: ") + error);
  }
  write_file_atomic(out_path, read_file((temp.path() / "spm.model").string(), size_t{1} << 30));
}

struct PieceModel::Handle {
  nec_spm_model* model = nullptr;
  ~Handle() {
    if (model != nullptr) bridge().free(model);
  }
};

PieceModel::PieceModel(PieceModel&&) noexcept = default;
PieceModel& PieceModel::operator=(PieceModel&&) noexcept = default;
PieceModel::~PieceModel() = default;

PieceModel PieceModel::load(const std::string& path) {
  if (!fs::is_regular_file(path)) {
    throw InputError(path, 0, "no such piece model; make one with `nec text train-tokenizer`");
  }
  const Bridge& spm = bridge();
  PieceModel out;
  out.path_ = path;
  out.handle_ = std::make_unique<Handle>();
  char error[kErrorSize] = {0};
  out.handle_->model = spm.load(path.c_str(), error, sizeof error);
  if (out.handle_->model == nullptr) {
    throw InputError(path, 0, std::string("not a sentencepiece model (") + error + ")");
  }
  const nec_spm_model* model = out.handle_->model;
  if (spm.pad_id(model) != kPadPiece || spm.unk_id(model) != kUnknownPiece) {
    throw InputError(path, 0, "a sentencepiece model with pad id " + std::to_string(spm.pad_id(model)) +
                                  " and unknown id " + std::to_string(spm.unk_id(model)) +
                                  ", not nec's 0 and 1; make one with `nec text train-tokenizer`");
  }
  out.vocab_size_ = spm.vocab_size(model);
  for (int id = 0; id < out.vocab_size_; ++id) {
    std::string piece(static_cast<size_t>(std::max(0, spm.piece(model, id, nullptr, 0))), '\0');
    spm.piece(model, id, piece.data(), piece.size() + 1);
    out.pieces_.push_back(std::move(piece));
  }
  return out;
}

void PieceModel::check(int id) const {
  if (id < 0 || id >= vocab_size_) {
    throw std::invalid_argument("piece id " + std::to_string(id) + " is outside the vocabulary of " +
                                std::to_string(vocab_size_) + " (" + path_ + ")");
  }
}

std::vector<int> PieceModel::encode(std::string_view text) const {
  const std::string input(text);
  std::vector<int32_t> ids(input.size() + 8);
  char error[kErrorSize] = {0};
  int count = bridge().encode(handle_->model, input.c_str(), ids.data(), static_cast<int>(ids.size()), error, sizeof error);
  if (count > static_cast<int>(ids.size())) {
    ids.resize(static_cast<size_t>(count));
    count = bridge().encode(handle_->model, input.c_str(), ids.data(), count, error, sizeof error);
  }
  if (count < 0) throw std::runtime_error(path_ + ": sentencepiece could not encode '" + input + "': " + error);
  return std::vector<int>(ids.begin(), ids.begin() + count);
}

std::string PieceModel::decode(const std::vector<int>& ids) const {
  for (const int id : ids) check(id);
  const std::vector<int32_t> input(ids.begin(), ids.end());
  std::string text(ids.size() * 8 + 16, '\0');
  char error[kErrorSize] = {0};
  int length = bridge().decode(handle_->model, input.data(), static_cast<int>(input.size()), text.data(), text.size(),
                               error, sizeof error);
  if (length >= static_cast<int>(text.size())) {
    text.assign(static_cast<size_t>(length) + 1, '\0');
    length = bridge().decode(handle_->model, input.data(), static_cast<int>(input.size()), text.data(), text.size(),
                             error, sizeof error);
  }
  if (length < 0) throw std::runtime_error(path_ + ": sentencepiece could not decode: " + error);
  text.resize(static_cast<size_t>(length));
  return text;
}

const std::string& PieceModel::piece(int id) const {
  check(id);
  return pieces_[static_cast<size_t>(id)];
}

bool PieceModel::starts_word(int id) const { return piece(id).rfind(kWordStart, 0) == 0; }

std::string PieceModel::piece_text(int id) const {
  const std::string& bytes = piece(id);
  return starts_word(id) ? bytes.substr(std::string_view(kWordStart).size()) : bytes;
}

CaptionPieces PieceModel::split(std::string_view normalized) const {
  CaptionPieces out;
  out.ids = encode(normalized);
  std::vector<std::string> joined;
  for (const int id : out.ids) {
    if (joined.empty() || starts_word(id)) joined.emplace_back();
    if (id != kUnknownPiece) joined.back() += piece_text(id);
    out.word_of_piece.push_back(static_cast<int>(joined.size()) - 1);
  }
  std::vector<std::string> words = caption_words(normalized);
  out.words = words.size() == joined.size() ? std::move(words) : std::move(joined);
  return out;
}

}  // namespace nec::text
