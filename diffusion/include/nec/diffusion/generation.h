// Text to motion on any skeleton with the diffusion model: what `nec generate
// --model DIFFUSION_DIR` runs.
//
//   DiffusionSession session = open_diffusion("runs/diffusion", /*glove=*/"");
//   const PreparedClip dragon = tat::prepare_for_model("dragon.bvh", session.fps(), UpAxis::Auto);
//   std::vector<Features> motions = generate_motions(session, dragon, {{"a dragon walks forward", 120}}, 2, options);
//   tat::write_onto(dragon, motions[0], corrections, 0.0, "dragon.bvh", "out.bvh", "a dragon walks forward");
//
// Several segments make one long motion: overlapping windows, each reading
// the caption of its segment, denoised together and blended at every step
// (windows.h); the motion starts facing +Z at the origin, as decoded tokens do.
#pragma once

#include "nec/diffusion/checkpoint.h"
#include "nec/diffusion/noise_schedule.h"
#include "nec/diffusion/sampling.h"
#include "nec/motion/features.h"
#include "nec/corpus/preprocess.h"
#include "nec/text/word_vectors.h"

#include <optional>
#include <string>
#include <vector>

namespace nec::diffusion {

struct DiffusionSession {
  LoadedDiffusion model;
  std::optional<text::WordVectors> vectors;  // read by the caption and OwO encoders when either reads words
  NoiseSchedule schedule;

  double fps() const { return model.info.fps; }
};

// Loads the motion-stage checkpoint `dir` and the word vectors it reads
// (`glove`, or the default file). InputError naming the file otherwise, and
// for a pose-stage checkpoint (it makes poses, not motion).
DiffusionSession open_diffusion(const std::string& dir, const std::string& glove);

struct DiffusionSegment {
  std::string caption;
  int64_t frames = 0;  // >= 1
};

// Θ (T, J, 9) of `samples` motions for the skeleton of `target` (a clip
// prepared for the model), each the segments in order. InputError for an
// empty caption or one longer than the text encoder takes.
std::vector<Features> generate_motions(DiffusionSession& session, const PreparedClip& target,
                                       const std::vector<DiffusionSegment>& segments, int samples,
                                       const DiffusionSamplingOptions& options);

}  // namespace nec::diffusion
