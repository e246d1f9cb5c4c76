/* The C interface of nec_spm_bridge, the one library that links Debian's
 * libsentencepiece. Its bundled protobuf clashes with libtorch's, so nec
 * opens this library with dlopen(RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND)
 * (text/sentencepiece.h) and nothing else links sentencepiece.
 *
 * Every function that can fail returns 0 (or a count) on success, and -1 on
 * failure with a NUL-terminated message in error[error_size] (cut to fit). */
#ifndef NEC_TEXT_SPM_BRIDGE_H
#define NEC_TEXT_SPM_BRIDGE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Bumped whenever a signature below changes; the loader checks it. */
#define NEC_SPM_BRIDGE_ABI 1
int nec_spm_abi(void);

/* sentencepiece's trainer with a command-line style option string, e.g.
 * "--input=captions.txt --model_prefix=/tmp/x/spm --vocab_size=1000". */
int nec_spm_train(const char* options, char* error, size_t error_size);

typedef struct nec_spm_model nec_spm_model;
/* A model file written by the trainer; NULL on failure. */
nec_spm_model* nec_spm_load(const char* path, char* error, size_t error_size);
void nec_spm_free(nec_spm_model* model);

int nec_spm_vocab_size(const nec_spm_model* model);
/* The special ids; -1 when the model has none. */
int nec_spm_pad_id(const nec_spm_model* model);
int nec_spm_unk_id(const nec_spm_model* model);

/* The piece ids of UTF-8 `text`: their count (ids[0, min(count, capacity)) are
 * written; call again with a bigger buffer when count > capacity), or -1. */
int nec_spm_encode(const nec_spm_model* model, const char* text, int32_t* ids, int capacity, char* error,
                   size_t error_size);
/* The text of ids, or of the one piece `id` (its bytes, "▁" marking a word
 * start): the length of the full result (out[0, out_size) holds a cut,
 * NUL-terminated copy), or -1. */
int nec_spm_decode(const nec_spm_model* model, const int32_t* ids, int count, char* out, size_t out_size, char* error,
                   size_t error_size);
int nec_spm_piece(const nec_spm_model* model, int id, char* out, size_t out_size);

#ifdef __cplusplus
}
#endif

#endif
