// Token files: a clip as motion tokens, independent of any skeleton
// (DESIGN.md, Files the tool writes).
//
//   {"format": "nec-tokens", "version": 1,
//    "fps": 30, "frames": 120, "downsampling": 4,
//    "codebook": {"layers": 4, "size": 256},
//    "model": {"kind": "nec-rvq", "training_step": 4000},
//    "source": {"file": "walk.bvh", "joints": 22, "scale": 17.3, "heading_degrees": 93.0},
//    "tokens": [[12, 200, 7, 31], ...]}          // (steps, layers), steps = ceil(frames / downsampling)
//
//   write_tokens("walk.tokens.json", tokens);             // atomic
//   TokenFile t = read_tokens("walk.tokens.json");        // InputError naming the file and field
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace nec::tat {

constexpr const char* kTokenFileFormat = "nec-tokens";
constexpr int kTokenFileVersion = 1;

struct TokenFile {
  double fps = 30.0;
  int frames = 0;                 // frames the tokens decode to
  int downsampling = 4;           // frames per token step
  int layers = 0;                 // R
  int codebook_size = 0;          // K
  std::string model_kind;         // e.g. "nec-rvq"
  int64_t training_step = 0;      // of the model that wrote them
  std::string source_file;        // where the motion came from
  int source_joints = 0;
  double source_scale = 1.0;      // the source's diameter in its file units
  double heading_degrees = 0.0;   // the source's frame-0 heading (yaw about up) in its file
  std::vector<int32_t> codes;     // (steps, layers) row-major

  int steps() const { return layers > 0 ? static_cast<int>(codes.size()) / layers : 0; }
};

void write_tokens(const std::string& path, const TokenFile& tokens);
// Checks format, version, shapes (steps = ceil(frames / downsampling)) and code
// ranges (0 <= code < size); throws nec::InputError naming the file and the problem.
TokenFile read_tokens(const std::string& path);

}  // namespace nec::tat
