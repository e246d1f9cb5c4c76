// A trained tokenizer at work on files: BVH in, tokens out, and tokens onto
// any skeleton as BVH in that file's own names, channels, units and up axis.
// What `nec encode | decode | transfer` (and later `nec generate`) run.
//
//   TokenizerSession session = open_tokenizer_session("runs/tat", /*glove=*/"", /*overlap_frames=*/-1);
//   const PreparedClip walk = prepare_for_model("walk.bvh", session.model.info.fps, UpAxis::Auto);
//   const TokenFile tokens = encode_file(session, walk, "walk.bvh");
//   decode_onto(session, tokens, "dragon.bvh", UpAxis::Auto, &stance, {&walk.clip}, "dragon_walk.bvh");
#pragma once

#include "nec/fitting/follow_ground.h"
#include "nec/fitting/follow_heading.h"
#include "nec/fitting/foot_lock.h"
#include "nec/corpus/preprocess.h"
#include "nec/corpus/stance.h"
#include "nec/fitting/step_feet.h"
#include "nec/tat/checkpoint.h"
#include "nec/tat/inference.h"
#include "nec/tat/tokens.h"
#include "nec/text/word_vectors.h"

#include <optional>
#include <string>
#include <vector>

namespace nec::tat {

// A loaded tokenizer with what it needs to embed skeletons.
struct TokenizerSession {
  LoadedTatCheckpoint model;
  std::optional<text::WordVectors> vectors;  // loaded when the OwO encoder reads joint names
  WindowOptions windows;

  // (J, D) joint embeddings of one normalized skeleton; undefined for the zero-padding baseline.
  at::Tensor embed(const Skeleton& skeleton, const std::vector<std::string>& canonical_names);
};

// Loads the checkpoint `model_dir` and the word vectors it reads (`glove`, or
// the default file when empty; their width checked). `overlap_frames`: frames
// neighbouring windows share, -1 for a quarter of the model's window (rounded
// down to a multiple of 2 r). Throws InputError for the files,
// std::invalid_argument for an overlap the windows cannot take.
TokenizerSession open_tokenizer_session(const std::string& model_dir, const std::string& glove,
                                        int64_t overlap_frames);

// read_bvh + preprocess at the model's fps; InputError naming the file when it is rejected.
PreparedClip prepare_for_model(const std::string& path, double fps, UpAxis up);
// The same for a skeleton that receives motion (generate --skeleton, transfer --to, decode --skeleton): its own
// motion is not used, so one frame (a rig exported in its bind pose) is enough. With `stance`, the rest the
// motion turns around is the stance `stance` reads from the file's frame 0 (corpus/stance.h), whatever pose the
// rig was given in; without (null), the mean pose of the file's motion, as for the clips the models learned from.
PreparedClip prepare_target(const std::string& path, double fps, UpAxis up, const StancePredictor* stance);

// The yaw (degrees, about the up axis) of a normalization's frame-0 heading,
// and a normalization that places normalized motion into `target`'s file
// (its scale, up axis and ground origin) with the heading `heading_degrees`.
double heading_degrees(const Normalization& normalization);
Normalization with_heading(const Normalization& target, double heading_degrees);

// Tokens of one clip prepared for the model; `path` names its file in the token file.
TokenFile encode_file(TokenizerSession& session, const PreparedClip& source, const std::string& path);

// What decode_onto does to the decoded motion before writing it.
struct DecodeCorrections {
  const Clip* source = nullptr;  // the clip the tokens came from, prepared for the model (a transfer), or none
  bool heading = true;           // with a source: turn body and path to face and go where it does
  bool ground = true;            // stand on the floor where the source stands (follow_ground), else settle onto it
  bool steps = true;             // with a source: feet that glide step in the source's rhythm (step_after)
  bool feet = true;              // pin the feet the motion puts down (lock_feet)
};

// What decode_onto did after decoding.
struct DecodeReport {
  std::optional<HeadingReport> heading;  // steered to follow a source's facing and path
  std::optional<GroundReport> ground;    // lifted or lowered onto the floor
  std::optional<StepReport> steps;       // gliding feet put down in the source's rhythm
  FootLockReport feet;
};

// Decodes tokens onto the skeleton of `target_path` (prepare_target with `stance`), applies `corrections` in
// their order above, and writes `out_path` (motion/clip_file.h): BVH in that
// file's units, up axis, joint names, channels and Euler orders, or a GLB copy
// of a target asset with the motion as a new animation. InputError when the
// tokens do not fit the model or the output cannot be written onto the target.
DecodeReport decode_onto(TokenizerSession& session, const TokenFile& tokens, const std::string& target_path, UpAxis up,
                         const StancePredictor* stance, const DecodeCorrections& corrections,
                         const std::string& out_path);
// The same onto `target`, the clip of `target_path` already prepared for the model (prepare_for_model at the
// model's fps): a command writing several motions onto one skeleton reads it once.
DecodeReport decode_onto(TokenizerSession& session, const TokenFile& tokens, const PreparedClip& target,
                         const std::string& target_path, const DecodeCorrections& corrections,
                         const std::string& out_path);

// What decode_onto does after decoding, for Θ from any model (e.g. a
// diffusion model's motion): `features` on `target` (the clip of
// `target_path` prepared for the model), corrected, placed into the file's
// frame with the heading `heading_degrees`, written to `out_path` with the
// animation name `animation` (asset outputs).
DecodeReport write_onto(const PreparedClip& target, const Features& features, const DecodeCorrections& corrections,
                        double heading_degrees, const std::string& target_path, const std::string& out_path,
                        const std::string& animation);

}  // namespace nec::tat
