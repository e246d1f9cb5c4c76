// The stance a rig's motion turns around, from its skeleton alone (DESIGN.md 5c).
//
//   PreparedClip rig = preprocess(read_clip("tpose_character.bvh"), "tpose_character.bvh");  // rest: its mean pose
//   PreparedClip stood = take_stance(rig, predictor);   // rest: the predicted stance of its creature
//   // stood.clip.skeleton's offsets are the stance's bone vectors; stood.normalization.rest_frames go back
//   // to the file's own joint frames exactly, as for any canonical rest.
//
// The models learn every motion as turns around a rig's canonical rest, the mean pose of its motion
// (rest_pose.h). A rig given without motion (one frame in its bind pose: a T-pose, an A-pose, whatever the
// rigger chose) has no mean pose but that frame, so a predictor (owo/stance.h) reads the bind pose and says
// where each bone points in the creature's typical stance. take_stance turns the rig into that stance:
//
// 1. the bind pose is the clip's frame 0: re-expressed with its global rotations (pose_frames), every joint
//    frame is world-aligned there and each offset is the bind pose's world bone vector (facing +Z, the
//    preprocessed frame), which is what the predictor reads;
// 2. the predictor gives each bone's stance direction d_j (the bone from j's parent to j);
// 3. stance_frames turns each joint by the world rotation R_j that best carries its child bones onto their
//    stance directions (Kabsch, weighted by bone length); where the children leave the turn about a bone
//    free (one child, or none) the parent's rotation decides it, so a chain swings without twisting;
// 4. re-expressing with R makes the stance the rest: offsets R_p b_j, world positions in every frame
//    unchanged, so the file's own motion (if any) is the same motion in other joint frames.
//
// Joint positions do not depend on the twist rule of step 3 (only offsets are read by the models, and the
// frames are world-aligned at rest); the joints' orientations written back to the file do.
#pragma once

#include "nec/corpus/preprocess.h"
#include "nec/motion/motion.h"

#include <string>
#include <vector>

namespace nec {

// Says where a creature's bones point in its typical stance, given its skeleton in a bind pose.
class StancePredictor {
 public:
  virtual ~StancePredictor() = default;
  // `bind`: normalized (diameter 1, +Y up, facing +Z), every joint frame world-aligned, so each offset is the
  // bind pose's world bone vector. Returns (J) unit stance directions of the bone into each joint, in the
  // same world frame; the root's entry and those of zero-length bones are not read.
  virtual std::vector<Vec3> bone_directions(const Skeleton& bind,
                                            const std::vector<std::string>& canonical_names) const = 0;
};

// The bind pose kept as the stance (every bone where the bind pose has it): what a rig without motion had
// before the stance network, the baseline its errors are measured against.
class BindPoseStance : public StancePredictor {
 public:
  std::vector<Vec3> bone_directions(const Skeleton& bind, const std::vector<std::string>&) const override;
};

// Every joint's global rotation at `frame`: the joint frames in which that pose is the rest.
std::vector<Quat> pose_frames(const Clip& clip, int frame);

// (J) unit offsets of the skeleton (the direction of the bone into each joint); zero for the root and for
// bones shorter than 1e-9.
std::vector<Vec3> unit_bones(const Skeleton& skeleton);

// The world rotations R_j (J) that turn `bind` (joint frames world-aligned) into the stance with bone
// directions `directions` (J): step 3 above. std::invalid_argument on a size mismatch.
std::vector<Quat> stance_frames(const Skeleton& bind, const std::vector<Vec3>& directions);

// A prepared clip (canonical rest, rest_frames set) put into its creature's stance as `predictor` reads it
// from the clip's frame 0; the report says so, and warns of a skeleton without limbs (one chain) and of chains
// of zero length (joints on their parents with nothing below them: they turn with their parents).
// std::invalid_argument for a clip without canonical rest frames or without frames.
PreparedClip take_stance(const PreparedClip& prepared, const StancePredictor& predictor);

// Angles (degrees) between the bone directions of two skeletons of one tree, one per joint whose bone is
// longer than 1e-9 in both: how far a predicted stance is from the true one. `lengths`, when given, gets the
// truth's length of each of those bones (to weigh a finger less than a thigh).
std::vector<double> bone_direction_errors(const Skeleton& predicted, const Skeleton& truth,
                                          std::vector<double>* lengths = nullptr);

// How a person's limbs hang and swing over a prepared clip (+Y up): what shows a stance taken or missed.
struct LimbAngles {
  bool found = false;              // the rig has left and right upper arms and upper legs (canonical names)
  double arms_from_hanging = 0.0;  // degrees between the upper arms and straight down, median over frames
  double thigh_swing = 0.0;        // degrees the thighs swing forward and back (5th to 95th percentile)
};
// The upper arm is the joint named "upper arm", else "arm" (CMU, Mixamo), else "shldr" (Poser), and its bone
// the one to its first child; the thigh likewise "upper leg", else "leg". Forward is across the thighs'
// left-right line.
LimbAngles measure_limbs(const Clip& normalized, const std::vector<std::string>& canonical_names);

}  // namespace nec
