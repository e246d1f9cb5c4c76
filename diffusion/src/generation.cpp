// Diffusion generation: checkpoint + word vectors, captions, skeleton inputs, samples as Θ.
#include "nec/diffusion/generation.h"

#include "nec/motion/error.h"
#include "nec/tat/inference.h"
#include "nec/tat/model_space.h"

#include <torch/torch.h>

#include <stdexcept>

namespace nec::diffusion {

DiffusionSession open_diffusion(const std::string& dir, const std::string& glove) {
  LoadedDiffusion loaded = load_diffusion_checkpoint(dir);
  if (loaded.info.stage != DiffusionStage::kMotion) {
    throw InputError(dir, 0, "is a pose-stage diffusion model (single frames); train its motion stage with "
                             "`nec train diffusion --stage motion --pose " + dir + "` and generate with that");
  }
  const int64_t word_dim = loaded.model->config().text.word_dim, name_dim = loaded.owo->encoder->config().name_dim;
  const int64_t noise_steps = loaded.model->config().noise_steps;
  DiffusionSession session{std::move(loaded), std::nullopt, NoiseSchedule(noise_steps)};
  if (word_dim > 0 || name_dim > 0) session.vectors.emplace(text::WordVectors::load_checked(glove, word_dim > 0 ? word_dim : name_dim));
  return session;
}

std::vector<Features> generate_motions(DiffusionSession& session, const PreparedClip& target,
                                       const std::vector<DiffusionSegment>& segments, int samples,
                                       const DiffusionSamplingOptions& options) {
  if (segments.empty() || samples < 1) throw std::invalid_argument("generate_motions: needs a segment and a sample");
  MotionDenoiserImpl& model = *session.model.model;
  c10::InferenceMode inference;
  const text::WordVectors* vectors = session.vectors ? &*session.vectors : nullptr;
  std::vector<std::string> captions;
  std::vector<int64_t> frames;
  for (const DiffusionSegment& segment : segments) {
    captions.push_back(segment.caption);
    frames.push_back(segment.frames);
  }
  const text::TextBatch text =
      session.model.captions.read(captions, vectors, segments.size() > 1 ? "the captions" : "the caption");
  const at::Tensor condition = model.caption_condition(text, {});
  at::Tensor joints;
  if (model.config().joint_identity != JointIdentity::kTree) {
    joints = tat::embed_skeletons(*session.model.owo->encoder, {target.clip.skeleton}, {target.canonical_names}, vectors)[0];
  } else {
    joints = torch::zeros({target.clip.skeleton.joint_count(), 1});
  }
  const SkeletonInputs skeleton = make_skeleton_inputs(target.clip.skeleton, joints);
  const std::vector<at::Tensor> motions =
      sample_motions(model, session.schedule, skeleton, condition, frames, samples, options);
  std::vector<Features> out;
  for (const at::Tensor& motion : motions) {
    const at::Tensor theta = tat::model_space_to_features(motion.unsqueeze(0), torch::zeros({1}))[0].contiguous();
    Features features;
    features.frame_count = static_cast<int>(theta.size(0));
    features.joint_count = static_cast<int>(theta.size(1));
    features.fps = session.fps();
    features.data.assign(theta.data_ptr<float>(), theta.data_ptr<float>() + theta.numel());
    out.push_back(std::move(features));
  }
  return out;
}

}  // namespace nec::diffusion
