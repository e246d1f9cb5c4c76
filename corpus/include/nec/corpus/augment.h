// Rig augmentation (NECromancer C.1; Dragon 4.2): new rigs for the same motion.
//
//   SplitMix64 rng(seed);                          // motion/random.h
//   Clip a = reset_rest_pose(clip, rng);          // global joint positions unchanged
//   Clip b = scale_bone_lengths(clip, names, rng); // per body part 0.8–1.2, left = right
//   Clip c = remove_joints(clip, rng);             // distal or zero-length joints
//   Clip d = subdivide_bones(clip, rng);           // insert a joint inside a bone
//
// Every function returns a clip whose joints are listed depth-first (as BVH
// files list them) and keeps the names of the joints it keeps.
#pragma once

#include "nec/motion/motion.h"
#include "nec/motion/random.h"

#include <string>
#include <vector>

namespace nec {

enum class AugmentKind { RestPose, BoneLength, JointRemoval, Subdivision };
// The names `nec augment --kind` and training configs use: "rest", "length", "remove", "subdivide".
std::string to_string(AugmentKind kind);
// Throws std::invalid_argument naming the known kinds.
AugmentKind augment_kind_from_string(const std::string& name);

// A random frame becomes the rest pose; offsets and rotations are recomputed
// so FK positions of every joint are unchanged.
Clip reset_rest_pose(const Clip& clip, SplitMix64& rng);
Clip reset_rest_pose_to_frame(const Clip& clip, int frame);

// Body part of a joint from its canonical name and chain: "spine", "neck",
// "head", "tail", "arm", "leg", "wing", "fin", "other". Left/right joints of
// the same part get the same factor.
std::vector<std::string> body_parts(const Skeleton& skeleton, const std::vector<std::string>& canonical_names);
Clip scale_bone_lengths(const Clip& clip, const std::vector<std::string>& canonical_names, SplitMix64& rng,
                        double min_factor = 0.8, double max_factor = 1.2);

// Joints that can be removed exactly: leaves (toe tips, head tips, tail ends)
// and joints whose children all sit at zero offset.
std::vector<int> removable_joints(const Skeleton& skeleton);
Clip remove_joint(const Clip& clip, int joint);
// Removes up to max(1, fraction × J) random removable joints.
Clip remove_joints(const Clip& clip, SplitMix64& rng, double fraction = 0.1);

// Inserts a joint at `fraction` along the bone from parent(joint) to joint.
Clip subdivide_bone(const Clip& clip, int joint, double fraction = 0.5);
Clip subdivide_bones(const Clip& clip, SplitMix64& rng, double fraction = 0.1);

// One random augmentation of the given kind.
Clip augment(const Clip& clip, AugmentKind kind, const std::vector<std::string>& canonical_names, SplitMix64& rng);

}  // namespace nec
