// nec_spm_bridge: the C interface of spm/bridge.h over libsentencepiece.
#include "bridge.h"

#include <sentencepiece_processor.h>
#include <sentencepiece_trainer.h>

#include <dlfcn.h>

#include <algorithm>
#include <cstring>
#include <iostream>
#include <new>
#include <sstream>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#define NEC_SPM_EXPORT extern "C" __attribute__((visibility("default")))

struct nec_spm_model {
  sentencepiece::SentencePieceProcessor processor;
};

namespace {

// Copies `text` into out[out_size] (cut, NUL-terminated); returns its full length.
int copy_out(const std::string& text, char* out, size_t out_size) {
  if (out != nullptr && out_size > 0) {
    const size_t n = std::min(text.size(), out_size - 1);
    std::memcpy(out, text.data(), n);
    out[n] = '\0';
  }
  return static_cast<int>(text.size());
}

int fail(const std::string& message, char* error, size_t error_size) {
  copy_out(message, error, error_size);
  return -1;
}

// Opened with RTLD_DEEPBIND, sentencepiece's references to std::cerr and its
// siblings bind to libstdc++'s own objects. A program that names std::cout
// itself gets copies of them (copy relocations), which are the ones libstdc++
// constructs: its own stay raw memory, and sentencepiece's first log line
// would crash. Each raw one becomes a stream on the program's buffer.
void adopt_program_stream(void* main_program, std::ostream& own, const char* symbol) {
  auto* program = static_cast<std::ostream*>(dlsym(main_program, symbol));
  if (program == nullptr || program == &own) return;
  new (&own) std::ostream(program->rdbuf());
}

__attribute__((constructor)) void adopt_program_streams() {
  void* main_program = dlopen(nullptr, RTLD_NOW);  // looks in the program first, then in what it loaded
  adopt_program_stream(main_program, std::cout, "_ZSt4cout");
  adopt_program_stream(main_program, std::cerr, "_ZSt4cerr");
  adopt_program_stream(main_program, std::clog, "_ZSt4clog");
}

}  // namespace

NEC_SPM_EXPORT int nec_spm_abi(void) { return NEC_SPM_BRIDGE_ABI; }

NEC_SPM_EXPORT int nec_spm_train(const char* options, char* error, size_t error_size) {
  // The trainer's log goes to a buffer: nothing on success, its end in the error otherwise.
  std::stringbuf log;
  std::streambuf* const terminal = std::cerr.rdbuf(&log);
  std::string problem;
  try {
    const sentencepiece::util::Status status = sentencepiece::SentencePieceTrainer::Train(options);
    if (!status.ok()) problem = status.ToString();
  } catch (const std::exception& e) {
    problem = e.what();
  }
  std::cerr.rdbuf(terminal);
  if (problem.empty()) return 0;
  const std::string text = log.str();
  return fail(problem + (text.empty() ? "" : " (log: ..." + text.substr(text.size() > 300 ? text.size() - 300 : 0) + ")"),
              error, error_size);
}

NEC_SPM_EXPORT nec_spm_model* nec_spm_load(const char* path, char* error, size_t error_size) {
  try {
    auto model = std::make_unique<nec_spm_model>();
    const sentencepiece::util::Status status = model->processor.Load(path);
    if (!status.ok()) {
      fail(status.ToString(), error, error_size);
      return nullptr;
    }
    return model.release();
  } catch (const std::exception& e) {
    fail(e.what(), error, error_size);
    return nullptr;
  }
}

NEC_SPM_EXPORT void nec_spm_free(nec_spm_model* model) { delete model; }

NEC_SPM_EXPORT int nec_spm_vocab_size(const nec_spm_model* model) { return model->processor.GetPieceSize(); }
NEC_SPM_EXPORT int nec_spm_pad_id(const nec_spm_model* model) { return model->processor.pad_id(); }
NEC_SPM_EXPORT int nec_spm_unk_id(const nec_spm_model* model) { return model->processor.unk_id(); }

NEC_SPM_EXPORT int nec_spm_encode(const nec_spm_model* model, const char* text, int32_t* ids, int capacity,
                                  char* error, size_t error_size) {
  try {
    std::vector<int> pieces;
    const sentencepiece::util::Status status = model->processor.Encode(text, &pieces);
    if (!status.ok()) return fail(status.ToString(), error, error_size);
    const int count = static_cast<int>(pieces.size());
    for (int i = 0; i < std::min(count, capacity); ++i) ids[i] = pieces[i];
    return count;
  } catch (const std::exception& e) {
    return fail(e.what(), error, error_size);
  }
}

NEC_SPM_EXPORT int nec_spm_decode(const nec_spm_model* model, const int32_t* ids, int count, char* out,
                                  size_t out_size, char* error, size_t error_size) {
  try {
    const std::vector<int> pieces(ids, ids + count);
    for (const int id : pieces) {
      if (id < 0 || id >= model->processor.GetPieceSize()) {
        return fail("piece id " + std::to_string(id) + " is outside the vocabulary of " +
                        std::to_string(model->processor.GetPieceSize()),
                    error, error_size);
      }
    }
    std::string text;
    const sentencepiece::util::Status status = model->processor.Decode(pieces, &text);
    if (!status.ok()) return fail(status.ToString(), error, error_size);
    return copy_out(text, out, out_size);
  } catch (const std::exception& e) {
    return fail(e.what(), error, error_size);
  }
}

NEC_SPM_EXPORT int nec_spm_piece(const nec_spm_model* model, int id, char* out, size_t out_size) {
  if (id < 0 || id >= model->processor.GetPieceSize()) return -1;
  return copy_out(model->processor.IdToPiece(id), out, out_size);
}
