// nec generate: motion from text on the user's own skeleton, through the GPT's tokens or the diffusion model.
#include "command_line.h"
#include "commands.h"
#include "model_options.h"
#include "torch_runtime.h"

#include "nec/diffusion/generation.h"
#include "nec/gpt/generation.h"
#include "nec/motion/clip_file.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/viewer/html.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <optional>
#include <utility>

namespace nec::app {
namespace {

namespace fs = std::filesystem;

constexpr double kMaxSeconds = 60.0;

// The caption sidecar of a BVH file: walk.bvh -> walk.txt (corpus/captions.h).
std::string sidecar_path(const std::string& bvh) { return fs::path(bvh).replace_extension(".txt").string(); }

// OUT.bvh for one sample; OUT_1.bvh ... OUT_K.bvh for K.
std::vector<std::string> output_paths(const std::string& out, int samples) {
  if (samples == 1) return {out};
  const fs::path path(out);
  std::vector<std::string> paths;
  for (int i = 1; i <= samples; ++i) {
    paths.push_back((path.parent_path() / (path.stem().string() + "_" + std::to_string(i) + path.extension().string())).string());
  }
  return paths;
}

// --seconds: "auto" (0 for every segment), one length for every segment, or one per segment ("3,2,4"); 0 = auto.
std::vector<double> segment_seconds(const std::string& value, size_t segments) {
  std::vector<double> seconds;
  size_t begin = 0;
  while (begin <= value.size()) {
    const size_t end = std::min(value.find(',', begin), value.size());
    const std::string item = value.substr(begin, end - begin);
    double length = 0;
    if (item != "auto") {
      char* rest = nullptr;
      length = std::strtod(item.c_str(), &rest);
      if (item.empty() || *rest != '\0' || !(length > 0 && length <= kMaxSeconds)) {
        throw InputError("--seconds", 0, fmt::format("'{}' is not a length in (0, {}] seconds or auto", item, kMaxSeconds));
      }
    }
    seconds.push_back(length);
    begin = end + 1;
  }
  if (seconds.size() == 1) return std::vector<double>(segments, seconds.front());
  if (seconds.size() != segments) {
    throw InputError("--seconds", 0, fmt::format("gives {} lengths for {} captions: give one for all, or one per caption",
                                                  seconds.size(), segments));
  }
  return seconds;
}

// Options of one kind of model, refused with another when changed from their defaults {option, default}.
void refuse_options(const CommandLine& cli, const std::vector<std::pair<std::string, std::string>>& options,
                    const std::string& kind) {
  for (const auto& [option, default_value] : options) {
    if (cli.value(option) != default_value) throw UsageError(option + " applies to " + kind + " models only");
  }
}

diffusion::DiffusionSolver parse_solver(const std::string& name) {
  if (name == "ddim") return diffusion::DiffusionSolver::kDdim;
  if (name == "dpm++") return diffusion::DiffusionSolver::kDpmSolver;
  throw UsageError("--solver must be dpm++ or ddim, got " + name);
}

diffusion::TimestepSpacing parse_spacing(const std::string& name) {
  if (name == "quadratic") return diffusion::TimestepSpacing::kQuadratic;
  if (name == "uniform") return diffusion::TimestepSpacing::kUniform;
  throw UsageError("--spacing must be quadratic or uniform, got " + name);
}

// A line saying how far the command is, out at once (nec serve shows a job's last line while it runs).
void progress(const std::string& line) {
  fmt::print("{}\n", line);
  std::fflush(stdout);
}

}  // namespace

int run_generate(int argc, char** argv) {
  CommandLine cli("nec generate",
                  "Motion from text for any skeleton, written in that file's own joint names, channels, Euler\n"
                  "orders, units and up axis, standing on its floor with its feet pinned, and its caption in\n"
                  "OUT.txt beside it (what `nec eval t2m` reads). With a GPT checkpoint the GPT writes tokens for\n"
                  "the caption and the skeleton and the tokenizer decodes them onto it; with a diffusion checkpoint\n"
                  "(`nec train diffusion`) the motion is denoised on the skeleton's joints directly. Several\n"
                  "captions make one long motion, each segment going on from the one before. --samples K writes\n"
                  "OUT_1.bvh ... OUT_K.bvh.");
  cli.positional("CAPTION", "what the motion shows, e.g. \"a dog walks forward\"; several: one segment each", true, true);
  cli.option("--skeleton", "SKELETON", "", "BVH file or rigged asset to generate for (its motion is not used)", true);
  cli.option("-o", "OUT", "", "output: .bvh, or .glb (a copy of the skeleton's asset with the motion added)", true);
  cli.option("--model", "CKPT", "", "GPT (`nec train gpt`) or diffusion (`nec train diffusion`) checkpoint, or\n"
                                    "gpt / diffusion: the default models' one; default: models/default/gpt");
  cli.option("--seconds", "S", "auto", "length of each segment (up to 60), or one per caption: 3,2,4; auto: the GPT\n"
                                       "ends it (diffusion: one window)");
  cli.option("--samples", "K", "1", "how many motions to write");
  cli.option("--seed", "N", "0", "sample i draws from seed + i");
  cli.option("--guidance", "G", "2.5", "classifier-free guidance scale (1: none)");
  cli.option("--temperature", "T", "1", "GPT: divides the logits (lower: safer, less varied)");
  cli.option("--top-k", "K", "0", "GPT: keep the K most likely codes (0: all)");
  cli.option("--top-p", "P", "0.95", "GPT: keep the fewest codes holding probability P (1: all)");
  cli.option("--steps", "N", "10", "diffusion: denoising steps (of the model's 1000)");
  cli.option("--solver", "NAME", "dpm++", "diffusion: dpm++ (DPM-Solver++, second order) or ddim");
  cli.option("--spacing", "NAME", "quadratic", "diffusion: the steps' timesteps, quadratic (more at low noise) or uniform");
  cli.option("--view", "PAGE.html", "", "also write a page that plays the motions");
  cli.option("--up", "AXIS", "auto", "up axis of the skeleton file: auto, y or z");
  cli.flag("--free-height", "keep the height as generated (default: settle the body onto the floor)");
  cli.flag("--free-feet", "leave the feet as generated (default: pin the feet the motion puts down)");
  cli.flag("--force", "overwrite output files that exist");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  cli.option("--threads", "N", "0", "torch threads; 0 = all cores");
  declare_stance_options(cli);
  cli.example("nec generate \"a dragon flaps its wings and takes off\" --skeleton dragon.bvh --model runs/gpt -o out.bvh");
  cli.example("nec generate \"a dog walks forward\" \"then it sits down\" --skeleton dog.bvh --model runs/gpt -o dog.bvh --seconds 3,2");
  cli.example("nec generate \"a spider walks forward quickly\" --skeleton spider.bvh --model runs/diffusion -o spider.bvh --samples 4 --view spider.html");
  if (!cli.parse(argc, argv)) return 0;
  const auto start = std::chrono::steady_clock::now();

  if (cli.integer("--seed") < 0) throw UsageError("--seed must be >= 0");
  const uint64_t seed = static_cast<uint64_t>(cli.integer("--seed"));
  const int samples = cli.integer("--samples");
  if (samples < 1 || samples > 256) throw UsageError("--samples must be in 1..256");
  const std::vector<std::string>& captions = cli.positionals("CAPTION");
  const std::vector<double> seconds = segment_seconds(cli.value("--seconds"), captions.size());
  // "gpt" and "diffusion" name the default models unless a checkpoint of that name is there.
  std::string model = cli.value("--model");
  if ((model == "gpt" || model == "diffusion") && checkpoint_format(model).empty()) {
    model = model_or_default("", model, "--model " + model);
  }
  model = model_or_default(model, "gpt", "--model");
  const bool is_diffusion = checkpoint_format(model) == diffusion::kDiffusionCheckpointFormat;
  gpt::SamplingOptions gpt_sampling;
  diffusion::DiffusionSamplingOptions diffusion_sampling;
  if (is_diffusion) {
    refuse_options(cli, {{"--temperature", "1"}, {"--top-k", "0"}, {"--top-p", "0.95"}}, "GPT");
    diffusion_sampling.steps = cli.integer("--steps");
    diffusion_sampling.solver = parse_solver(cli.value("--solver"));
    diffusion_sampling.spacing = parse_spacing(cli.value("--spacing"));
    diffusion_sampling.guidance = cli.number("--guidance");
    diffusion_sampling.seed = seed;
    diffusion_sampling.on_step = [](int64_t step, int64_t steps) { progress(fmt::format("denoising step {}/{}", step + 1, steps)); };
  } else {
    refuse_options(cli, {{"--steps", "10"}, {"--solver", "dpm++"}, {"--spacing", "quadratic"}}, "diffusion");
    gpt_sampling.temperature = cli.number("--temperature");
    gpt_sampling.top_k = cli.integer("--top-k");
    gpt_sampling.top_p = cli.number("--top-p");
    gpt_sampling.guidance = cli.number("--guidance");
    gpt_sampling.seed = seed;
    gpt_sampling.on_segment = [&captions](size_t segment, size_t segments) {
      progress(fmt::format("segment {}/{}: {}", segment + 1, segments, captions[segment]));
    };
  }
  try {
    if (is_diffusion) {
      diffusion_sampling.validate();
    } else {
      gpt_sampling.validate();
    }
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const std::vector<std::string> outputs = output_paths(cli.value("-o"), samples);
  const std::string view = cli.value("--view");
  std::vector<std::string> written;
  for (const std::string& path : outputs) {
    written.push_back(path);
    written.push_back(sidecar_path(path));
  }
  if (!view.empty()) written.push_back(view);
  check_clip_output(cli.value("-o"), cli.value("--skeleton"));
  for (const std::string& path : written) {
    if (!cli.is_set("--force") && fs::exists(path)) throw InputError(path, 0, "exists; pass --force to overwrite it");
    const fs::path folder = fs::path(path).parent_path();
    if (!folder.empty() && !fs::is_directory(folder)) throw InputError(path, 0, "its folder does not exist");
  }

  use_torch_threads(threads_option(cli));
  const UpAxis up = cli.up_axis("--up");
  std::string caption;
  for (const std::string& segment : captions) caption += (caption.empty() ? "" : " / ") + segment;
  tat::DecodeCorrections corrections;
  corrections.heading = false;
  corrections.ground = !cli.is_set("--free-height");
  corrections.feet = !cli.is_set("--free-feet");

  // Sample i written to outputs[i]; returns its frame count.
  std::function<int(int)> write_sample;
  double fps = 30.0;
  std::shared_ptr<gpt::GeneratorSession> gpt_session;
  std::shared_ptr<diffusion::DiffusionSession> diffusion_session;
  std::vector<at::Tensor> codes;
  std::vector<Features> motions;
  std::optional<PreparedClip> target;
  const Stance stance = open_stance(cli, cli.value("--glove"));
  const std::string model_key = files_stamp(model) + "\n" + glove_stamp(cli.value("--glove"));
  if (is_diffusion) {
    diffusion_session = warm<diffusion::DiffusionSession>(WarmKind::Model, model_key,
                                                          [&] { return diffusion::open_diffusion(model, cli.value("--glove")); });
    fps = diffusion_session->fps();
    const int64_t noise_steps = diffusion_session->model.model->config().noise_steps;
    if (diffusion_sampling.steps > noise_steps) {
      throw UsageError(fmt::format("--steps {} is more than the model's {} noise steps", diffusion_sampling.steps, noise_steps));
    }
    target = prepare_target(cli.value("--skeleton"), fps, up, stance);
    const int64_t window = diffusion_session->model.model->config().max_frames;
    std::vector<diffusion::DiffusionSegment> segments;
    for (size_t i = 0; i < captions.size(); ++i) {
      segments.push_back({captions[i], seconds[i] > 0 ? std::max<int64_t>(4, std::lround(seconds[i] * fps)) : window});
    }
    motions = diffusion::generate_motions(*diffusion_session, *target, segments, samples, diffusion_sampling);
    write_sample = [&](int i) {
      tat::write_onto(*target, motions[static_cast<size_t>(i)], corrections, 0.0, cli.value("--skeleton"),
                      outputs[static_cast<size_t>(i)], caption);
      return motions[static_cast<size_t>(i)].frame_count;
    };
  } else {
    gpt_session = warm<gpt::GeneratorSession>(WarmKind::Model, model_key,
                                              [&] { return gpt::open_generator(model, cli.value("--glove")); });
    fps = gpt_session->fps();
    target = prepare_target(cli.value("--skeleton"), fps, up, stance);
    std::vector<gpt::Segment> segments;
    for (size_t i = 0; i < captions.size(); ++i) {
      const int64_t steps = std::max<int64_t>(1, std::lround(seconds[i] * fps / gpt_session->downsampling()));
      segments.push_back({captions[i], seconds[i] > 0 ? steps : 0});
    }
    codes = gpt::generate_codes(*gpt_session, *target, segments, samples, gpt_sampling);
    write_sample = [&](int i) {
      const tat::TokenFile tokens = gpt_session->token_file(codes[static_cast<size_t>(i)], caption);
      tat::decode_onto(gpt_session->tokenizer, tokens, *target, cli.value("--skeleton"), corrections,
                      outputs[static_cast<size_t>(i)]);
      return tokens.frames;
    };
  }

  std::vector<viewer::ViewClip> views;
  for (int i = 0; i < samples; ++i) {
    const int frames = write_sample(i);
    std::string lines;
    for (const std::string& segment : captions) lines += segment + "\n";
    write_file_atomic(sidecar_path(outputs[static_cast<size_t>(i)]), lines);
    fmt::print("wrote {}: {} frames ({:.1f} s) on the skeleton of {}\n", outputs[static_cast<size_t>(i)], frames,
               frames / fps, cli.value("--skeleton"));
    if (!view.empty()) {
      viewer::ViewClip clip = viewer::load_view_clip(outputs[static_cast<size_t>(i)]);
      clip.captions = {caption};
      views.push_back(std::move(clip));
    }
  }
  if (!view.empty()) {
    viewer::ViewOptions options;
    options.title = "nec generate: " + caption;
    options.up = up;
    write_file_atomic(view, viewer::make_view_html(views, options));
    fmt::print("wrote {}\n", view);
  }
  fmt::print("{} motion(s) in {:.2f} s\n", samples,
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}

}  // namespace nec::app
