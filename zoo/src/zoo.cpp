// The zoo writer: creatures x clips -> BVH + caption sidecars + manifest.
#include "nec/zoo/zoo.h"

#include "nec/motion/bvh.h"
#include "nec/motion/files.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace nec::zoo {
namespace {

namespace fs = std::filesystem;

constexpr int kManifestVersion = 1;

std::string_view naming_name(NamingStyle naming) {
  switch (naming) {
    case NamingStyle::Mixamo: return "mixamo";
    case NamingStyle::Blender: return "blender";
    case NamingStyle::Game: return "game";
    case NamingStyle::Biped3ds: return "biped3ds";
    case NamingStyle::Numbered: return "numbered";
    case NamingStyle::Maya: return "maya";
    case NamingStyle::Truebones: return "truebones";
  }
  return "unknown";
}

std::string_view rest_pose_name(RestPose pose) {
  switch (pose) {
    case RestPose::TPose: return "t_pose";
    case RestPose::APose: return "a_pose";
    case RestPose::Crouched: return "crouched";
  }
  return "unknown";
}

std::string_view side_name(Side side) {
  switch (side) {
    case Side::Left: return "left";
    case Side::Right: return "right";
    case Side::None: return "none";
  }
  return "none";
}

std::vector<BodyPlan> plans_in_rotation(const ZooOptions& options) {
  if (!options.plans.empty()) return options.plans;
  return std::vector<BodyPlan>(std::begin(kAllBodyPlans), std::end(kAllBodyPlans));
}

bool is_held_out(const ZooOptions& options, BodyPlan plan) {
  return std::find(options.held_out_plans.begin(), options.held_out_plans.end(), plan) != options.held_out_plans.end();
}

// The action of each clip: the plan's actions in a seeded order, reshuffled every round.
// The actions a creature's clips are drawn from: what its plan supports, among the options' actions.
std::vector<Action> drawn_actions(BodyPlan plan, const ZooOptions& options) {
  std::vector<Action> actions = supported_actions(plan);
  if (options.actions.empty()) return actions;
  actions.erase(std::remove_if(actions.begin(), actions.end(),
                               [&](Action a) {
                                 return std::find(options.actions.begin(), options.actions.end(), a) ==
                                        options.actions.end();
                               }),
                actions.end());
  return actions;
}

Action clip_action(const Creature& creature, const ZooOptions& options, int clip_index) {
  std::vector<Action> actions = drawn_actions(creature.plan, options);
  const int n = static_cast<int>(actions.size());
  SplitMix64 random(mix_seed(creature.seed, 0xAC7100 + static_cast<uint64_t>(clip_index / n)));
  for (int i = n - 1; i > 0; --i) std::swap(actions[i], actions[random.below(i + 1)]);
  return actions[clip_index % n];
}

nlohmann::json clip_json(const ZooClip& clip, const Creature& creature) {
  nlohmann::json j;
  j["file"] = clip.bvh_file;
  j["captions_file"] = clip.captions_file;
  j["held_out"] = clip.held_out;
  j["creature"] = {
      {"index", clip.creature_index},
      {"plan", std::string(body_plan_name(clip.plan))},
      {"seed", clip.creature_seed},
      {"species", clip.species},
      {"joints", clip.joint_count},
      {"naming", std::string(naming_name(creature.options.naming))},
      {"rest_pose", std::string(rest_pose_name(creature.options.rest_pose))},
      {"euler_order", std::string(euler_order_name(creature.options.euler_order))},
      {"body_length", creature.body_length},
      {"leg_length", creature.leg_length},
  };
  j["clip_index"] = clip.clip_index;
  j["clip_seed"] = clip.clip_seed;
  j["action"] = std::string(action_name(clip.spec.action));
  j["parameters"] = {
      {"speed_body_lengths_per_second", clip.spec.speed},
      {"typical_speed_body_lengths_per_second", typical_speed(creature, clip.spec.action)},
      {"turn_rate_degrees_per_second", clip.spec.turn_rate},
      {"direction_degrees", clip.spec.direction},
      {"manner", std::string(manner_name(clip.spec.manner))},
      {"heading_change_degrees", heading_change_degrees(clip.spec)},
      {"start_from_still", clip.spec.start_from_still},
      {"stop_at_end", clip.spec.stop_at_end},
      {"side", std::string(side_name(clip.spec.side))},
      {"seconds", clip.spec.seconds},
      {"fps", clip.spec.fps},
      {"frames", clip.frames},
      {"gait_frequency_hz", clip.gait_frequency},
  };
  j["captions"] = {{"short", clip.captions.short_text}, {"mid", clip.captions.mid_text}, {"long", clip.captions.long_text}};
  return j;
}

void make_folder(const fs::path& path) {
  std::error_code error;
  fs::create_directories(path, error);
  if (error) throw std::runtime_error("cannot create folder " + path.string() + ": " + error.message());
}

}  // namespace

void ZooOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("ZooOptions: " + what); };
  if (out_dir.empty()) fail("out_dir is empty");
  if (creatures < 1) fail("creatures must be >= 1, got " + std::to_string(creatures));
  if (clips_per_creature < 1) fail("clips_per_creature must be >= 1, got " + std::to_string(clips_per_creature));
  const std::vector<BodyPlan> rotation = plans_in_rotation(*this);
  for (BodyPlan plan : held_out_plans) {
    if (std::find(rotation.begin(), rotation.end(), plan) == rotation.end()) {
      fail("held-out plan '" + std::string(body_plan_name(plan)) + "' is not among the plans");
    }
  }
  for (BodyPlan plan : rotation) {
    if (drawn_actions(plan, *this).empty()) {
      fail("a " + std::string(body_plan_name(plan)) + " supports none of the actions asked for");
    }
  }
  MotionSpec spec;
  spec.seconds = seconds;
  spec.fps = fps;
  spec.validate();
}

BodyPlan zoo_creature_plan(const ZooOptions& options, int index) {
  const std::vector<BodyPlan> rotation = plans_in_rotation(options);
  return rotation[static_cast<size_t>(index) % rotation.size()];
}

uint64_t zoo_creature_seed(const ZooOptions& options, int index) {
  return mix_seed(options.seed, static_cast<uint64_t>(index));
}

MotionSpec zoo_clip_spec(const Creature& creature, const ZooOptions& options, int clip_index) {
  const uint64_t clip_seed = mix_seed(creature.seed, 1 + static_cast<uint64_t>(clip_index));
  SplitMix64 random(clip_seed);
  MotionSpec spec;
  spec.action = clip_action(creature, options, clip_index);
  spec.seconds = options.seconds;
  spec.fps = options.fps;
  spec.seed = clip_seed;
  const double typical = typical_speed(creature, spec.action);
  spec.speed = typical * random.uniform(0.5, 1.8);
  if (spec.action == Action::Jump) spec.speed = random.chance(0.4) ? 0.0 : typical * random.uniform(0.6, 1.6);
  if (spec.action == Action::TakeOff) spec.speed = typical * random.uniform(0.7, 1.4);
  if (is_locomotion(spec.action)) {
    const double sign = random.chance(0.5) ? 1.0 : -1.0;
    const double kind = random.uniform();
    if (spec.action == Action::Turn) {
      spec.turn_rate = sign * random.uniform(45.0, 120.0);
    } else if (kind < 0.4) {
      spec.turn_rate = 0.0;
    } else if (kind < 0.7) {
      spec.turn_rate = sign * random.uniform(12.0, 30.0);
    } else {
      spec.turn_rate = sign * random.uniform(40.0, 90.0);
    }
    const bool airborne = spec.action == Action::Fly || spec.action == Action::Glide;
    spec.start_from_still = !airborne && random.chance(0.35);
    spec.stop_at_end = !airborne && random.chance(0.3);
    const bool crab_gait = spec.action == Action::Walk || spec.action == Action::Run;
    if (creature.plan == BodyPlan::Crab && crab_gait && random.chance(0.75)) {
      spec.direction = random.chance(0.5) ? 90.0 : -90.0;  // crabs walk and run sideways
    } else if (spec.action == Action::Walk && random.chance(0.3)) {
      const double directions[] = {180.0, 90.0, -90.0};  // backs up, sidesteps left, sidesteps right
      spec.direction = directions[random.below(3)];
    }
  }
  if (takes_manner(spec.action) && random.chance(0.35)) {
    // A manner, with a pace that suits it.
    const Manner manners[] = {Manner::Tired, Manner::Energetic, Manner::Cautious, Manner::Proud};
    spec.manner = manners[random.below(4)];
    if (is_locomotion(spec.action) && spec.action != Action::Turn) {
      if (spec.manner == Manner::Tired || spec.manner == Manner::Cautious) spec.speed = typical * random.uniform(0.4, 0.85);
      if (spec.manner == Manner::Energetic) spec.speed = typical * random.uniform(1.1, 1.8);
    }
  }
  if (spec.action == Action::Attack || spec.action == Action::Point || spec.action == Action::Kick) {
    spec.side = random.chance(0.5) ? Side::Left : Side::Right;
  }
  if (spec.action == Action::Wave || spec.action == Action::RaiseHands) {
    const Side sides[] = {Side::Left, Side::Right, Side::None};  // None: both hands
    spec.side = sides[random.below(3)];
  }
  return spec;
}

ZooSummary write_zoo(const ZooOptions& options, const std::function<void(const ZooClip&)>& on_clip) {
  options.validate();
  const fs::path root(options.out_dir);
  ZooSummary summary;
  nlohmann::json clips = nlohmann::json::array();
  for (int i = 0; i < options.creatures; ++i) {
    const BodyPlan plan = zoo_creature_plan(options, i);
    const uint64_t creature_seed = zoo_creature_seed(options, i);
    const Creature creature = make_creature(plan, creature_seed);
    const bool held_out = is_held_out(options, plan);
    const std::string creature_name = fmt::format("c{:03d}_{}", i, body_plan_name(plan));
    const fs::path folder = fs::path(held_out ? "held_out" : "seen") / creature_name;
    make_folder(root / folder);
    ++summary.creatures;
    if (held_out) ++summary.held_out_creatures;
    for (int k = 0; k < options.clips_per_creature; ++k) {
      const MotionSpec requested = zoo_clip_spec(creature, options, k);
      const SynthesizedMotion made = synthesize_motion(creature, requested);
      ZooClip clip;
      const std::string stem = fmt::format("{}_k{:02d}_{}", creature_name, k, action_name(made.spec.action));
      clip.bvh_file = (folder / (stem + ".bvh")).generic_string();
      clip.captions_file = (folder / (stem + ".txt")).generic_string();
      clip.creature_index = i;
      clip.plan = plan;
      clip.creature_seed = creature_seed;
      clip.species = creature.species;
      clip.joint_count = creature.skeleton.joint_count();
      clip.held_out = held_out;
      clip.clip_index = k;
      clip.clip_seed = requested.seed;
      clip.spec = made.spec;
      clip.gait_frequency = made.gait_frequency;
      clip.frames = made.motion.frame_count;
      clip.captions = caption_motion(creature, made.spec, mix_seed(requested.seed, 0xCA9));
      write_bvh((root / clip.bvh_file).string(), creature.skeleton, made.motion);
      std::string text;
      for (const std::string& line : clip.captions.lines()) text += line + "\n";
      write_file_atomic((root / clip.captions_file).string(), text);
      clips.push_back(clip_json(clip, creature));
      if (on_clip) on_clip(clip);
      summary.clips.push_back(std::move(clip));
    }
  }
  nlohmann::json manifest;
  manifest["format"] = "nec-zoo";
  manifest["version"] = kManifestVersion;
  manifest["seed"] = options.seed;
  manifest["creatures"] = options.creatures;
  manifest["clips_per_creature"] = options.clips_per_creature;
  manifest["seconds"] = options.seconds;
  manifest["fps"] = options.fps;
  nlohmann::json plans = nlohmann::json::array();
  for (BodyPlan plan : plans_in_rotation(options)) plans.push_back(std::string(body_plan_name(plan)));
  manifest["plans"] = plans;
  nlohmann::json held = nlohmann::json::array();
  for (BodyPlan plan : options.held_out_plans) held.push_back(std::string(body_plan_name(plan)));
  manifest["held_out_plans"] = held;
  manifest["layout"] = "seen/<creature>/<clip>.bvh and held_out/<creature>/<clip>.bvh, captions in <clip>.txt (short, mid, long)";
  manifest["clips"] = clips;
  summary.manifest_path = (root / "manifest.json").string();
  write_file_atomic(summary.manifest_path, manifest.dump(2) + "\n");
  return summary;
}

}  // namespace nec::zoo
