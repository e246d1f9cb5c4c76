// Tokens from BVH files and BVH from tokens, with a loaded tokenizer.
#include "nec/tat/session.h"

#include "nec/motion/clip_file.h"
#include "nec/motion/error.h"
#include "nec/motion/rotations.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <cmath>
#include <filesystem>

namespace nec::tat {
namespace {

// The up-axis part of a normalization's rotation: +Y (normalized) -> the file's up.
Quat up_part(const Normalization& n) {
  const Vec3 up = n.rotation * Vec3::UnitY();
  return Quat::FromTwoVectors(Vec3::UnitY(), up).normalized();
}

}  // namespace

at::Tensor TokenizerSession::embed(const Skeleton& skeleton, const std::vector<std::string>& canonical_names) {
  if (model.tokenizer->config().kind == TokenizerKind::ZeroPadRvq) return {};
  return embed_skeletons(*model.owo->encoder, {skeleton}, {canonical_names}, vectors ? &*vectors : nullptr)[0];
}

TokenizerSession open_tokenizer_session(const std::string& model_dir, const std::string& glove,
                                        int64_t overlap_frames) {
  TokenizerSession session;
  session.model = load_tat_checkpoint(model_dir);
  const int64_t name_dim = session.model.owo->encoder->config().name_dim;
  // Also for the zero-padding baseline, whose tokens do not read the OwO: the GPT's skeleton features do.
  if (name_dim > 0) {
    session.vectors.emplace(text::WordVectors::load_checked(glove, name_dim));
  }
  session.windows.window_frames = session.model.info.window_frames;
  const int64_t step = 2 * session.model.tokenizer->config().downsampling();
  session.windows.overlap_frames = overlap_frames >= 0 ? overlap_frames : session.windows.window_frames / 4 / step * step;
  session.windows.validate(session.model.tokenizer->config().downsampling());
  return session;
}

namespace {

PreparedClip prepare_at(const std::string& path, double fps, UpAxis up, int min_frames) {
  PreprocessOptions options;
  options.target_fps = fps;
  options.up = up;
  options.min_frames = min_frames;
  return preprocess_file(path, options);
}

}  // namespace

PreparedClip prepare_for_model(const std::string& path, double fps, UpAxis up) { return prepare_at(path, fps, up, 2); }

PreparedClip prepare_target(const std::string& path, double fps, UpAxis up, const StancePredictor* stance) {
  const PreparedClip prepared = prepare_at(path, fps, up, 1);
  return stance ? take_stance(prepared, *stance) : prepared;
}

double heading_degrees(const Normalization& n) {
  const Quat yaw = (up_part(n).conjugate() * n.rotation).normalized();
  return heading_angle(yaw) * kDegreesPerRadian;
}

Normalization with_heading(const Normalization& target, double degrees) {
  Normalization out = target;
  const double half = 0.5 * degrees / kDegreesPerRadian;
  const Quat yaw(std::cos(half), 0.0, std::sin(half), 0.0);
  out.rotation = (up_part(target) * yaw).normalized();
  return out;
}

TokenFile encode_file(TokenizerSession& session, const PreparedClip& source, const std::string& path) {
  const Features features = encode_features(source.clip.skeleton, source.clip.motion);
  const at::Tensor codes = encode_clip(*session.model.tokenizer, features,
                                            session.embed(source.clip.skeleton, source.canonical_names),
                                            session.windows)
                               .to(torch::kInt32)
                               .contiguous();
  const TatConfig& config = session.model.tokenizer->config();
  TokenFile tokens;
  tokens.fps = session.model.info.fps;
  tokens.frames = features.frame_count;
  tokens.downsampling = static_cast<int>(config.downsampling());
  tokens.layers = static_cast<int>(config.quantizer.layers);
  tokens.codebook_size = static_cast<int>(config.quantizer.codebook_size);
  tokens.model_kind = to_string(config.kind);
  tokens.training_step = session.model.info.training_step;
  tokens.source_file = path;
  tokens.source_joints = source.clip.skeleton.joint_count();
  tokens.source_scale = source.normalization.scale;
  tokens.heading_degrees = heading_degrees(source.normalization);
  tokens.codes.assign(codes.data_ptr<int32_t>(), codes.data_ptr<int32_t>() + codes.numel());
  return tokens;
}

namespace {

// The name of a written animation (in an asset output): the caption of generated tokens, else the source's file.
std::string animation_name(const TokenFile& tokens) {
  const std::string generated = "generated: ";
  if (tokens.source_file.rfind(generated, 0) == 0) return tokens.source_file.substr(generated.size());
  return std::filesystem::path(tokens.source_file).filename().string();
}

}  // namespace

DecodeReport decode_onto(TokenizerSession& session, const TokenFile& tokens, const std::string& target_path,
                         UpAxis up, const StancePredictor* stance, const DecodeCorrections& corrections,
                         const std::string& out_path) {
  return decode_onto(session, tokens, prepare_target(target_path, session.model.info.fps, up, stance), target_path,
                     corrections, out_path);
}

DecodeReport decode_onto(TokenizerSession& session, const TokenFile& tokens, const PreparedClip& target,
                         const std::string& target_path, const DecodeCorrections& corrections,
                         const std::string& out_path) {
  const TatConfig& config = session.model.tokenizer->config();
  if (tokens.layers > config.quantizer.layers || tokens.codebook_size != config.quantizer.codebook_size ||
      tokens.downsampling != config.downsampling()) {
    throw InputError(tokens.source_file, 0,
                     fmt::format("tokens of a {}-layer x {} codebook at downsampling {} do not fit this model "
                                 "({} x {}, downsampling {}); decode with the model that encoded them",
                                 tokens.layers, tokens.codebook_size, tokens.downsampling, config.quantizer.layers,
                                 config.quantizer.codebook_size, config.downsampling()));
  }
  const Skeleton& skeleton = target.clip.skeleton;
  const at::Tensor codes =
      torch::from_blob(const_cast<int32_t*>(tokens.codes.data()), {tokens.steps(), tokens.layers}, torch::kInt32)
          .to(torch::kInt64);
  const Features features =
      decode_clip(*session.model.tokenizer, codes, tokens.frames, session.embed(skeleton, target.canonical_names),
                       skeleton, tokens.fps, session.windows);
  return write_onto(target, features, corrections, tokens.heading_degrees, target_path, out_path,
                    animation_name(tokens));
}

DecodeReport write_onto(const PreparedClip& target, const Features& features, const DecodeCorrections& corrections,
                        double heading_degrees, const std::string& target_path, const std::string& out_path,
                        const std::string& animation) {
  Clip out{target.clip.skeleton, decode_features(target.clip.skeleton, features), {}};
  DecodeReport report;
  const Clip* source = corrections.source;
  if (source != nullptr && corrections.heading) report.heading = follow_heading(*source, out.skeleton, out.motion);
  if (corrections.ground) {
    report.ground = source != nullptr ? follow_ground(*source, out.skeleton, out.motion)
                                      : settle_on_ground(out.skeleton, out.motion);
  }
  if (source != nullptr && corrections.steps) report.steps = step_after(*source, out.skeleton, out.motion);
  if (corrections.feet) report.feet = lock_feet(out.skeleton, out.motion);
  out = denormalize(out, with_heading(target.normalization, heading_degrees));
  write_clip(out_path, out, target_path, animation);
  return report;
}

}  // namespace nec::tat
