// The skeletons OwO pretrains and is evaluated on: every distinct skeleton of
// one or more dataset caches, split so that whole body plans (or any skeletons
// a pattern names) are held out for evaluation, and rig augmentations of the
// training skeletons drawn on the fly.
//
//   std::vector<PretrainSkeleton> all = skeletons_from_cache(read_cache("zoo_cache"), /*poses=*/16, /*seed=*/1);
//   HoldOut hold_out;  hold_out.patterns = {"spider", "snake"};
//   SkeletonSet set = split_skeleton_set(all, hold_out);   // set.train, set.held_out
//   SplitMix64 rng(step);
//   AugmentedSkeleton rig = augment_skeleton(set.train[3], AugmentOptions{}, rng);  // new rest pose, lengths, joints
//
// A hold-out pattern ('*' and '?' wildcards) takes a skeleton when it matches
// one of its labels: the skeleton's name or hash in the cache, the dataset of
// one of its clips, one of its clips' source paths, or a word of such a path
// (split at / \ _ - . and spaces). So "spider" takes every creature that
// `nec zoo` wrote under .../c004_spider/, "bandai" a whole dataset, and
// "*/held_out/*" whatever lies in such a folder. Skeletons are identified by
// their content hash: one found in two caches is one skeleton, and a skeleton
// held out anywhere is never trained on.
#pragma once

#include "nec/corpus/dataset.h"
#include "nec/motion/motion.h"
#include "nec/motion/random.h"

#include <cstdint>
#include <string>
#include <vector>

namespace nec::train {
class ConfigVisitor;
}

namespace nec::owo {

struct PretrainSkeleton {
  std::string name;                          // the cache's label, e.g. "zoo-14"
  std::string hash;                          // the cache's content hash, e.g. "3f2a9c0d11e4b7a8"
  std::string group;                         // why it is where it is: the hold-out pattern that took it,
                                             // "cache test split", or "train"
  Skeleton skeleton;                         // normalized rest pose (diameter 1 in a cache)
  std::vector<std::string> canonical_names;  // (J) e.g. "left upper leg"
  std::vector<std::string> labels;           // what hold-out patterns are matched against
  bool held_out_by_cache = false;            // the cache's own split holds it out (nec prepare --hold-out ...)
  Motion poses;                              // a few frames of its clips: rest poses for augmentation (may be 0 frames)
};

// One entry per distinct skeleton of `cache`, in cache order, with up to
// `poses_per_skeleton` frames sampled evenly over its clips (deterministic for `seed`).
std::vector<PretrainSkeleton> skeletons_from_cache(const DatasetCache& cache, int poses_per_skeleton, uint64_t seed);

// What to keep out of training.
struct HoldOut {
  std::vector<std::string> patterns;  // e.g. {"spider", "snake"}; see the file comment
  bool cache_held_out = true;         // also hold out what the caches themselves hold out
};

struct SkeletonSet {
  std::vector<PretrainSkeleton> train;
  std::vector<PretrainSkeleton> held_out;
  std::vector<std::string> unmatched_patterns;  // hold-out patterns that took no skeleton
};

// Merges duplicates (same hash: labels joined, the first entry's data kept),
// then splits. Held-out skeletons keep input order, grouped by the first
// pattern that matches (patterns before the caches' own hold-out).
SkeletonSet split_skeleton_set(const std::vector<PretrainSkeleton>& skeletons, const HoldOut& hold_out);

// True when `pattern` matches one of the skeleton's labels.
bool matches_hold_out(const PretrainSkeleton& skeleton, const std::string& pattern);

// Rig augmentation of one skeleton (corpus/augment.h, on its rest pose).
struct AugmentOptions {
  double probability = 0.8;       // chance that a sample is augmented at all, e.g. 0.8
  double rest_pose = 0.5;         // chance of a rest pose taken from one of its poses (NECromancer C.1)
  double bone_length = 0.5;       // chance of bone lengths scaled by body part (Dragon 4.2)
  double min_bone_factor = 0.8;   // bone length factor range, e.g. 0.8 - 1.2
  double max_bone_factor = 1.2;
  double joint_removal = 0.3;     // chance of removing distal / zero-length joints
  double subdivision = 0.3;       // chance of inserting joints inside bones
  double joint_fraction = 0.1;    // share of joints removed or inserted, e.g. 0.1

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, AugmentOptions& c);  // train/config_fields.h

struct AugmentedSkeleton {
  Skeleton skeleton;                         // valid, joints depth-first, root 0
  std::vector<std::string> canonical_names;  // (J) of the new joints
};

// Draws one augmentation (possibly none) of `skeleton`. Kept joints keep their
// names; canonical names are recomputed from the file names.
AugmentedSkeleton augment_skeleton(const PretrainSkeleton& skeleton, const AugmentOptions& options, SplitMix64& rng);

}  // namespace nec::owo
