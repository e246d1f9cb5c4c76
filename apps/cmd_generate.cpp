// nec generate: motion from text on the user's own skeleton, through the GPT's tokens.
#include "command_line.h"
#include "commands.h"
#include "model_options.h"
#include "torch_runtime.h"

#include "nec/gpt/generation.h"
#include "nec/motion/clip_file.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/viewer/html.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <chrono>
#include <cmath>
#include <filesystem>

namespace nec::app {
namespace {

namespace fs = std::filesystem;

constexpr double kMaxSeconds = 60.0;

// The caption sidecar of a BVH file: walk.bvh -> walk.txt (motion/captions.h).
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

}  // namespace

int run_generate(int argc, char** argv) {
  CommandLine cli("nec generate",
                  "Motion from text for any skeleton: the GPT writes tokens for the caption and the skeleton, the\n"
                  "tokenizer decodes them onto it, and the BVH is written in that file's own joint names, channels,\n"
                  "Euler orders, units and up axis, standing on its floor with its feet pinned, and its caption\n"
                  "in OUT.txt beside it (what `nec eval t2m` reads). Several captions make one long motion, each\n"
                  "segment going on from the one before. --samples K writes OUT_1.bvh ... OUT_K.bvh.");
  cli.positional("CAPTION", "what the motion shows, e.g. \"a dog walks forward\"; several: one segment each", true, true);
  cli.option("--skeleton", "SKELETON", "", "BVH file or rigged asset to generate for (its motion is not used)", true);
  cli.option("-o", "OUT", "", "output: .bvh, or .glb (a copy of the skeleton's asset with the motion added)", true);
  cli.option("--model", "GPT_CKPT", "", "GPT checkpoint (from `nec train gpt`); default: models/default/gpt");
  cli.option("--seconds", "S", "auto", "length of each segment (up to 60); auto: the GPT ends it");
  cli.option("--samples", "K", "1", "how many motions to write");
  cli.option("--seed", "N", "0", "sample i draws from seed + i");
  cli.option("--temperature", "T", "1", "divides the logits (lower: safer, less varied)");
  cli.option("--top-k", "K", "0", "keep the K most likely codes (0: all)");
  cli.option("--top-p", "P", "0.95", "keep the fewest codes holding probability P (1: all)");
  cli.option("--guidance", "G", "2.5", "classifier-free guidance scale (1: none)");
  cli.option("--view", "PAGE.html", "", "also write a page that plays the motions");
  cli.option("--up", "AXIS", "auto", "up axis of the skeleton file: auto, y or z");
  cli.flag("--free-height", "keep the height as decoded (default: settle the body onto the floor)");
  cli.flag("--free-feet", "leave the feet as decoded (default: pin the feet the motion puts down)");
  cli.flag("--force", "overwrite output files that exist");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  cli.option("--threads", "N", "0", "torch threads; 0 = all cores");
  cli.example("nec generate \"a dragon flaps its wings and takes off\" --skeleton dragon.bvh --model runs/gpt -o out.bvh");
  cli.example("nec generate \"a dog walks forward\" \"then it sits down\" --skeleton dog.bvh --model runs/gpt -o dog.bvh --seconds 3");
  cli.example("nec generate \"a spider walks forward quickly\" --skeleton spider.bvh --model runs/gpt -o spider.bvh --samples 4 --view spider.html");
  if (!cli.parse(argc, argv)) return 0;
  const auto start = std::chrono::steady_clock::now();

  gpt::SamplingOptions sampling;
  sampling.temperature = cli.number("--temperature");
  sampling.top_k = cli.integer("--top-k");
  sampling.top_p = cli.number("--top-p");
  sampling.guidance = cli.number("--guidance");
  if (cli.integer("--seed") < 0) throw UsageError("--seed must be >= 0");
  sampling.seed = static_cast<uint64_t>(cli.integer("--seed"));
  try {
    sampling.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const int samples = cli.integer("--samples");
  if (samples < 1 || samples > 256) throw UsageError("--samples must be in 1..256");
  double seconds = 0;
  if (cli.value("--seconds") != "auto") {
    seconds = cli.number("--seconds");
    if (!(seconds > 0 && seconds <= kMaxSeconds)) {
      throw InputError("--seconds", 0, fmt::format("{} is out of range: give a length in (0, {}] seconds, or auto",
                                                    cli.value("--seconds"), kMaxSeconds));
    }
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
  const std::string model = model_or_default(cli.value("--model"), "gpt", "--model");
  gpt::GeneratorSession session = gpt::open_generator(model, cli.value("--glove"));
  const UpAxis up = cli.up_axis("--up");
  const PreparedClip target = tat::prepare_for_model(cli.value("--skeleton"), session.fps(), up);
  std::vector<gpt::Segment> segments;
  for (const std::string& caption : cli.positionals("CAPTION")) {
    const int64_t steps = seconds > 0 ? std::max<int64_t>(1, std::lround(seconds * session.fps() / session.downsampling())) : 0;
    segments.push_back({caption, steps});
  }
  const std::vector<at::Tensor> codes = gpt::generate_codes(session, target, segments, samples, sampling);

  std::string caption;
  for (const gpt::Segment& segment : segments) caption += (caption.empty() ? "" : " / ") + segment.caption;
  tat::DecodeCorrections corrections;
  corrections.heading = false;
  corrections.ground = !cli.is_set("--free-height");
  corrections.feet = !cli.is_set("--free-feet");
  std::vector<viewer::ViewClip> views;
  for (int i = 0; i < samples; ++i) {
    const tat::TokenFile tokens = session.token_file(codes[static_cast<size_t>(i)], caption);
    tat::decode_onto(session.tokenizer, tokens, cli.value("--skeleton"), up, corrections, outputs[static_cast<size_t>(i)]);
    std::string lines;
    for (const gpt::Segment& segment : segments) lines += segment.caption + "\n";
    write_file_atomic(sidecar_path(outputs[static_cast<size_t>(i)]), lines);
    fmt::print("wrote {}: {} frames ({:.1f} s) on the skeleton of {}\n", outputs[static_cast<size_t>(i)], tokens.frames,
               tokens.frames / session.fps(), cli.value("--skeleton"));
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
