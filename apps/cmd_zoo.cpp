// nec zoo: write procedural creatures with captioned clips (BVH + clip.txt + manifest).
#include "command_line.h"
#include "commands.h"

#include "nec/motion/error.h"
#include "nec/zoo/zoo.h"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>

namespace nec::app {
namespace {

// A comma-separated list of names (or "all": empty), each parsed by `parse`; an unknown one is a usage error
// that lists the known names.
template <typename T, size_t N, typename Parse, typename Name>
std::vector<T> parse_name_list(const CommandLine& cli, const std::string& option, const std::string& what,
                               const T (&known)[N], Parse parse, Name name) {
  std::vector<T> out;
  if (cli.value(option) == "all") return out;
  for (const std::string& item : cli.list(option)) {
    T value;
    if (!parse(item, value)) {
      std::string names;
      for (const T& k : known) names += (names.empty() ? "" : " ") + std::string(name(k));
      throw UsageError(option + ": unknown " + what + " '" + item + "' (known: " + names + ")");
    }
    out.push_back(value);
  }
  return out;
}

std::vector<zoo::BodyPlan> parse_plan_list(const CommandLine& cli, const std::string& option) {
  return parse_name_list(cli, option, "body plan", zoo::kAllBodyPlans, zoo::parse_body_plan, zoo::body_plan_name);
}

uint64_t parse_seed(const std::string& text) {
  try {
    size_t used = 0;
    const unsigned long long value = std::stoull(text, &used);
    if (used == text.size() && text.find('-') == std::string::npos) return value;
  } catch (const std::exception&) {
  }
  throw UsageError("--seed must be a non-negative integer, got '" + text + "'");
}

std::vector<zoo::Action> parse_action_list(const CommandLine& cli, const std::string& option) {
  return parse_name_list(cli, option, "action", zoo::kAllActions, zoo::parse_action, zoo::action_name);
}

// "  biped      idle walk run ..." per plan, for the help.
std::string actions_by_plan() {
  std::string out;
  for (zoo::BodyPlan plan : zoo::kAllBodyPlans) {
    out += fmt::format("\n  {:<12}", zoo::body_plan_name(plan));
    for (zoo::Action action : zoo::supported_actions(plan)) out += " " + std::string(zoo::action_name(action));
  }
  return out;
}

}  // namespace

int run_zoo(int argc, char** argv) {
  CommandLine cli("nec zoo",
                  "Write a zoo of procedural creatures with captioned clips: DIR/seen/<creature>/<clip>.bvh +\n"
                  "<clip>.txt (short, mid and long caption, one per line, as `nec prepare` reads them), held-out\n"
                  "plans under DIR/held_out/, and DIR/manifest.json describing every clip. Creature i has plan i\n"
                  "mod the number of plans; every choice comes from the seed: speed, turning, walks that back up\n"
                  "or sidestep, the side of a gesture, and a manner (tired, energetic, cautious, proud) for a third\n"
                  "of the gaits and idles. Body plans and their actions:" +
                      actions_by_plan());
  cli.option("--out", "DIR", "", "output folder", true);
  cli.option("--creatures", "N", "9", "number of creatures");
  cli.option("--clips-per-creature", "M", "4", "clips per creature");
  cli.option("--seed", "S", "0", "seed of every choice");
  cli.option("--plans", "LIST", "all", "body plans in rotation, comma-separated, or all");
  cli.option("--hold-out", "LIST", "", "body plans (comma-separated) written under DIR/held_out/ instead of DIR/seen/");
  cli.option("--actions", "LIST", "all", "actions (comma-separated) clips are drawn from, or all");
  cli.option("--seconds", "SECONDS", "4", "clip length");
  cli.option("--fps", "FPS", "30", "frames per second");
  cli.flag("--quiet", "print only the summary");
  cli.flag("--force", "replace DIR when it holds anything (without it, a folder that is not empty is refused)");
  cli.example("nec zoo --out zoo --creatures 9 --clips-per-creature 4 --seed 1 --hold-out spider,dragon");
  cli.example("nec zoo --out gestures --plans biped --actions wave,clap,kick --creatures 2 --clips-per-creature 3");
  if (!cli.parse(argc, argv)) return 0;

  zoo::ZooOptions options;
  options.out_dir = cli.value("--out");
  options.creatures = cli.integer("--creatures");
  options.clips_per_creature = cli.integer("--clips-per-creature");
  options.seed = parse_seed(cli.value("--seed"));
  options.plans = parse_plan_list(cli, "--plans");
  options.held_out_plans = parse_plan_list(cli, "--hold-out");
  options.actions = parse_action_list(cli, "--actions");
  options.seconds = cli.number("--seconds");
  options.fps = cli.number("--fps");
  try {
    options.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  // A zoo written over another would mix their clips (different creatures keep their files): refuse, or replace.
  const std::filesystem::path out_dir(options.out_dir);
  if (std::filesystem::exists(out_dir) &&
      (!std::filesystem::is_directory(out_dir) || !std::filesystem::is_empty(out_dir))) {
    if (!cli.is_set("--force")) throw InputError(options.out_dir, 0, "is not empty; pass --force to replace it");
    std::filesystem::remove_all(out_dir);
  }
  const bool quiet = cli.is_set("--quiet");
  const auto start = std::chrono::steady_clock::now();
  const zoo::ZooSummary summary = zoo::write_zoo(options, [&](const zoo::ZooClip& clip) {
    if (quiet) return;
    fmt::print("{}  {} {}  {} joints  {:.2f} bl/s  turn {:+.0f} deg/s  \"{}\"\n", clip.bvh_file, clip.species,
               zoo::action_name(clip.spec.action), clip.joint_count, clip.spec.speed, clip.spec.turn_rate,
               clip.captions.mid_text);
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fmt::print("wrote {} clips of {} creatures ({} held out) to {} in {:.2f} s; manifest {}\n", summary.clips.size(),
             summary.creatures, summary.held_out_creatures, options.out_dir, seconds, summary.manifest_path);
  return 0;
}

}  // namespace nec::app
