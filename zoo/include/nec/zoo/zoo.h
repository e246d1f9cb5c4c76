// A zoo on disk: procedural creatures of many body plans, each with captioned
// clips, in the layout `nec prepare` reads (clip.bvh + clip.txt sidecar).
//
//   ZooOptions options;
//   options.out_dir = "zoo";
//   options.creatures = 9;
//   options.clips_per_creature = 4;
//   options.held_out_plans = {BodyPlan::Spider};
//   ZooSummary summary = write_zoo(options);
//   // nec prepare zoo=zoo/seen -o cache/      (held-out plans stay unseen)
//
// Layout:
//   DIR/manifest.json                          every clip: files, creature, action, parameters, captions
//   DIR/seen/c000_biped/c000_biped_k00_walk.bvh   + c000_biped_k00_walk.txt (short, mid, long caption)
//   DIR/held_out/c003_spider/...               creatures of the held-out plans
//
// Every choice comes from the seed: creature i has plan plans[i % plans.size()]
// and creature seed mix_seed(seed, i); its clips' actions, speeds, turns and
// phrasings come from mix_seed(creature seed, clip index). Same options -> the
// same files, byte for byte. Each file is written atomically; the manifest last.
#pragma once

#include "nec/zoo/zoo_captions.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace nec::zoo {

struct ZooOptions {
  std::string out_dir;                  // output folder, created if missing
  int creatures = 9;                    // number of creatures, e.g. 9
  int clips_per_creature = 4;           // clips per creature, e.g. 4
  uint64_t seed = 0;                    // every choice derives from it
  std::vector<BodyPlan> plans;          // plans in rotation; empty = all nine
  std::vector<BodyPlan> held_out_plans; // written under held_out/ instead of seen/; must be among the plans
  std::vector<Action> actions;          // actions clips are drawn from (each creature: those its plan supports);
                                        // empty = all; every plan in rotation must support at least one
  double seconds = 4.0;                 // clip length, e.g. 4
  double fps = 30.0;                    // frames per second, e.g. 30

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

struct ZooClip {
  std::string bvh_file;       // relative to out_dir, e.g. "seen/c000_biped/c000_biped_k00_walk.bvh"
  std::string captions_file;  // the sidecar next to it, ".txt"
  int creature_index = 0;
  BodyPlan plan = BodyPlan::Biped;
  uint64_t creature_seed = 0;
  std::string species;        // e.g. "dog"
  int joint_count = 0;
  bool held_out = false;
  int clip_index = 0;
  uint64_t clip_seed = 0;
  MotionSpec spec;            // as made (SynthesizedMotion::spec)
  double gait_frequency = 0;  // stride cycles per second, 0 without a gait
  int frames = 0;
  Captions captions;
};

struct ZooSummary {
  std::vector<ZooClip> clips;  // in creature, clip order
  std::string manifest_path;   // out_dir/manifest.json
  int creatures = 0;
  int held_out_creatures = 0;
};

// The plan of creature `index` and its seed.
BodyPlan zoo_creature_plan(const ZooOptions& options, int index);
uint64_t zoo_creature_seed(const ZooOptions& options, int index);
// The spec of clip `clip_index` of a creature (before the synthesizer clamps it).
MotionSpec zoo_clip_spec(const Creature& creature, const ZooOptions& options, int clip_index);

// Writes the zoo. `on_clip` (optional) is called after each clip is written.
ZooSummary write_zoo(const ZooOptions& options, const std::function<void(const ZooClip&)>& on_clip = {});

}  // namespace nec::zoo
