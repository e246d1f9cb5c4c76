// nec encode | decode | transfer: motion to tokens and tokens onto any skeleton.
#include "command_line.h"
#include "commands.h"
#include "model_options.h"

#include "nec/motion/clip_file.h"
#include "nec/motion/error.h"
#include "nec/tat/session.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <chrono>
#include <optional>

namespace nec::app {
namespace {

void declare_correction_options(CommandLine& cli) {
  cli.flag("--free-height", "keep the height as decoded (default: lift or lower the body to stand on the floor where\n"
                            "the source stands; without a source, onto the floor where it stands near it)");
  cli.flag("--free-feet", "leave the feet as decoded (default: pin the feet the motion puts down and bend their legs\n"
                          "to reach the pins, as decoded feet slide)");
}

tat::DecodeCorrections corrections(const CommandLine& cli, const Clip* source) {
  tat::DecodeCorrections out;
  out.source = source;
  out.heading = source != nullptr && !cli.is_set("--free-heading");  // only transfer declares --free-heading
  out.ground = !cli.is_set("--free-height");
  out.steps = source != nullptr && !cli.is_set("--free-steps");  // only transfer declares --free-steps
  out.feet = !cli.is_set("--free-feet");
  return out;
}

std::string decode_summary(const tat::DecodeReport& report) {
  std::string out;
  if (report.heading) {
    out += fmt::format("; steered to face and go as the source does (body turned {:.1f}° on average, {:.1f}° at "
                       "most; path {:.1f}° at most)",
                       report.heading->mean_turn, report.heading->max_turn, report.heading->max_path_turn);
  }
  if (report.ground && report.ground->max_shift > 0.0) {
    out += fmt::format("; {} onto the floor ({:.3f} body sizes on average, {:.3f} at most)",
                       report.ground->mean_shift > 0.0 ? "moved" : "kept", report.ground->mean_shift,
                       report.ground->max_shift);
  }
  if (report.steps && report.steps->feet > 0) {
    const StepReport& steps = *report.steps;
    out += fmt::format("; {} gliding feet stepped, {} plants, at {:.2f} strides/s (the source's {:.2f}; largest "
                       "miss {:.3f} sizes)",
                       steps.feet, steps.plants, steps.strides_per_second, steps.source_strides_per_second,
                       steps.max_miss);
  }
  const FootLockReport& feet = report.feet;
  if (feet.feet > 0) {
    out += fmt::format("; {} plants of {} feet pinned (they slid {:.2f} body sizes/s; largest miss {:.3f} sizes)",
                       feet.planted_spans, feet.feet, feet.mean_slide, feet.max_miss);
  }
  return out;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int run_encode(int argc, char** argv) {
  CommandLine cli("nec encode",
                  "Turn a BVH clip into motion tokens (JSON) with a trained tokenizer. Long clips are encoded\n"
                  "in overlapping windows of the training length.");
  cli.positional("IN", "input BVH file or rigged asset (IN#NAME: one animation of an asset)");
  cli.option("-o", "TOKENS.json", "", "output token file", true);
  cli.option("--up", "AXIS", "auto", "up axis of the input: auto, y or z");
  declare_model_options(cli);
  cli.example("nec encode walk.bvh --model runs/tat -o walk.tokens.json");
  if (!cli.parse(argc, argv)) return 0;
  const auto start = std::chrono::steady_clock::now();
  const std::shared_ptr<tat::TokenizerSession> opened = open_tokenizer(tokenizer_options(cli));
  tat::TokenizerSession& session = *opened;
  const std::string& path = cli.positional_value("IN");
  const tat::TokenFile tokens =
      tat::encode_file(session, tat::prepare_for_model(path, session.model.info.fps, cli.up_axis("--up")), path);
  tat::write_tokens(cli.value("-o"), tokens);
  fmt::print("wrote {}: {} frames -> {} token steps x {} layers ({:.2f} s)\n", cli.value("-o"), tokens.frames,
             tokens.steps(), tokens.layers, seconds_since(start));
  return 0;
}

int run_decode(int argc, char** argv) {
  CommandLine cli("nec decode",
                  "Decode motion tokens onto a skeleton: the output BVH has the skeleton file's joint names,\n"
                  "channels, Euler orders, units and up axis; the motion keeps the heading it was encoded with.");
  cli.positional("TOKENS.json", "token file from `nec encode`");
  cli.option("--skeleton", "TARGET", "", "BVH file or rigged asset whose skeleton receives the motion (its motion is ignored)",
             true);
  cli.option("-o", "OUT", "", "output: .bvh, or .glb (a copy of the target asset with the motion added)", true);
  cli.option("--up", "AXIS", "auto", "up axis of the skeleton file: auto, y or z");
  declare_correction_options(cli);
  declare_model_options(cli);
  declare_stance_options(cli);
  cli.example("nec decode walk.tokens.json --skeleton dragon.bvh --model runs/tat -o dragon_walk.bvh");
  if (!cli.parse(argc, argv)) return 0;
  check_clip_output(cli.value("-o"), cli.value("--skeleton"));
  const auto start = std::chrono::steady_clock::now();
  const std::shared_ptr<tat::TokenizerSession> opened = open_tokenizer(tokenizer_options(cli));
  tat::TokenizerSession& session = *opened;
  const tat::TokenFile tokens = tat::read_tokens(cli.positional_value("TOKENS.json"));
  const Stance stance = open_stance(cli, cli.value("--glove"));
  const PreparedClip target = prepare_target(cli.value("--skeleton"), session.model.info.fps, cli.up_axis("--up"),
                                             stance);
  const tat::DecodeReport report = tat::decode_onto(session, tokens, target, cli.value("--skeleton"),
                                                    corrections(cli, nullptr), cli.value("-o"));
  fmt::print("wrote {}: {} frames on the skeleton of {}{} ({:.2f} s)\n", cli.value("-o"), tokens.frames,
             cli.value("--skeleton"), decode_summary(report), seconds_since(start));
  return 0;
}

int run_transfer(int argc, char** argv) {
  CommandLine cli("nec transfer",
                  "Move a clip onto another skeleton (any species): encode SRC to tokens with its own skeleton,\n"
                  "decode them with the target's. The output uses the target file's joint names, channels, Euler\n"
                  "orders, units and up axis; speed scales with the target's size; it faces and goes where the source does\n"
                  "and steps in its rhythm.");
  cli.positional("SRC", "the motion to transfer: BVH file or rigged asset (SRC#NAME: one animation of an asset)");
  cli.option("--to", "TARGET", "", "BVH file or rigged asset whose skeleton receives the motion", true);
  cli.option("-o", "OUT", "", "output: .bvh, or .glb (a copy of the target asset with the motion added)", true);
  cli.option("--up", "AXIS", "auto", "up axis of both input files: auto, y or z");
  cli.option("--tokens", "FILE", "", "also write the intermediate tokens here");
  cli.flag("--free-heading", "keep heading and path as decoded (default: turn the output's body and path slowly\n"
                             "to face and go where the source does over time, as the decoded turning drifts)");
  cli.flag("--free-steps", "leave gliding feet as decoded (default: where the output's feet glide along with its body\n"
                           "while the source's step, put them down in the source's rhythm and bend the legs to reach)");
  declare_correction_options(cli);
  declare_model_options(cli);
  declare_stance_options(cli);
  cli.example("nec transfer human_wave.bvh --to dragon.bvh --model runs/tat -o dragon_wave.bvh");
  cli.example("nec transfer walk.bvh --to /usr/share/assimp/models/X/Testwuson.X -o wuson_walk.glb");
  if (!cli.parse(argc, argv)) return 0;
  check_clip_output(cli.value("-o"), cli.value("--to"));
  const auto start = std::chrono::steady_clock::now();
  const std::shared_ptr<tat::TokenizerSession> opened = open_tokenizer(tokenizer_options(cli));
  tat::TokenizerSession& session = *opened;
  const std::string& path = cli.positional_value("SRC");
  const PreparedClip source = tat::prepare_for_model(path, session.model.info.fps, cli.up_axis("--up"));
  const tat::TokenFile tokens = tat::encode_file(session, source, path);
  const Stance stance = open_stance(cli, cli.value("--glove"));
  const PreparedClip target = prepare_target(cli.value("--to"), session.model.info.fps, cli.up_axis("--up"),
                                             stance);
  const tat::DecodeReport report =
      tat::decode_onto(session, tokens, target, cli.value("--to"), corrections(cli, &source.clip), cli.value("-o"));
  if (!cli.value("--tokens").empty()) tat::write_tokens(cli.value("--tokens"), tokens);
  fmt::print("wrote {}: {} frames of {} on the skeleton of {}{} ({:.2f} s)\n", cli.value("-o"), tokens.frames, path,
             cli.value("--to"), decode_summary(report), seconds_since(start));
  return 0;
}

}  // namespace nec::app
