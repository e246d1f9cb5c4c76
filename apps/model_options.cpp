// Shared steps of the commands that run a trained tokenizer.
#include "model_options.h"

#include "torch_runtime.h"

#include <torch/torch.h>

#include <cmath>
#include <thread>

namespace nec::app {
namespace {

// The up-axis part of a normalization's rotation: +Y (normalized) -> the file's up.
Quat up_part(const Normalization& n) {
  const Vec3 up = n.rotation * Vec3::UnitY();
  return Quat::FromTwoVectors(Vec3::UnitY(), up).normalized();
}

}  // namespace

void declare_model_options(CommandLine& cli, bool with_model) {
  if (with_model) cli.option("--model", "CKPT", "", "tokenizer checkpoint directory (from `nec train tat`)", true);
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  cli.option("--threads", "N", "0", "torch threads; 0 = all cores");
  cli.option("--window-overlap", "FRAMES", "auto",
             "frames shared by neighbouring windows of long clips (auto: a quarter of the model's window)");
}

at::Tensor TokenizerSession::embed(const Skeleton& skeleton, const std::vector<std::string>& canonical_names) {
  if (model.tokenizer->config().kind == tat::TokenizerKind::ZeroPadRvq) return {};
  return tat::embed_skeletons(*model.owo->encoder, {skeleton}, {canonical_names}, vectors ? &*vectors : nullptr)[0];
}

TokenizerOptions tokenizer_options(const CommandLine& cli) {
  TokenizerOptions options;
  if (cli.declared("--model")) options.model = cli.value("--model");
  options.glove = cli.value("--glove");
  options.threads = threads_option(cli);
  if (cli.value("--window-overlap") != "auto") {
    options.overlap_frames = cli.integer("--window-overlap");
    if (options.overlap_frames < 0) throw UsageError("--window-overlap must be >= 0 or auto");
  }
  return options;
}

TokenizerSession open_tokenizer(const TokenizerOptions& options) {
  use_torch_threads(options.threads);
  TokenizerSession session;
  session.model = tat::load_tat_checkpoint(options.model);
  if (session.model.owo->encoder->config().name_dim > 0 &&
      session.model.tokenizer->config().kind != tat::TokenizerKind::ZeroPadRvq) {
    session.vectors.emplace(text::WordVectors::load_checked(options.glove, session.model.owo->encoder->config().name_dim));
  }
  session.windows.window_frames = session.model.info.window_frames;
  const int64_t step = 2 * session.model.tokenizer->config().downsampling();
  session.windows.overlap_frames =
      options.overlap_frames >= 0 ? options.overlap_frames : session.windows.window_frames / 4 / step * step;
  try {
    session.windows.validate(session.model.tokenizer->config().downsampling());
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--window-overlap: ") + e.what());
  }
  return session;
}

PreparedClip prepare_for_model(const std::string& path, double fps, UpAxis up) {
  PreprocessOptions options;
  options.target_fps = fps;
  options.up = up;
  return preprocess_file(path, options);
}

double heading_degrees(const Normalization& n) {
  const Quat yaw = (up_part(n).conjugate() * n.rotation).normalized();
  return heading_angle(yaw) * 180.0 / M_PI;
}

Normalization with_heading(const Normalization& target, double degrees) {
  Normalization out = target;
  const double half = degrees * M_PI / 360.0;
  const Quat yaw(std::cos(half), 0.0, std::sin(half), 0.0);
  out.rotation = (up_part(target) * yaw).normalized();
  return out;
}

}  // namespace nec::app
