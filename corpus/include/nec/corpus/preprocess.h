// Unified preprocessing (DESIGN.md steps 1–7; NECromancer appendix B).
//
//   PreparedClip p = preprocess(read_bvh(path), path, PreprocessOptions{});
//   if (!p.report.accepted()) std::cerr << p.report.rejection;
//   Clip original = denormalize(p.clip, p.normalization);   // back to file units and heading
//
// Steps: merge dummy roots outside the body; fold constant non-root position
// channels into offsets (reject varying ones); reject abnormal bone lengths;
// compute canonical names; scale by the diameter; rotate so +Y is up and frame
// 0 faces +Z with the root above the origin; resample to the corpus fps;
// re-express the joints in the canonical rest (corpus/rest_pose.h: the mean
// pose, world-aligned joint frames), so that no model sees how the rig was
// authored. Every change and the reason of a rejection is recorded in the report.
#pragma once

#include "nec/motion/features.h"
#include "nec/motion/motion.h"

#include <string>
#include <vector>

namespace nec {

enum class UpAxis { Auto, Y, Z };

struct PreprocessOptions {
  double target_fps = 30.0;             // corpus frame rate, e.g. 30; 0 keeps the file's rate
  double max_bone_ratio = 0.9;          // reject a bone longer than this times the diameter (one bone dominating the longest chain)
  // Non-root position channels are folded into offsets (their mean) when they vary by at most
  // translation_tolerance × diameter and translation_bone_tolerance × the bone's length (exports jitter
  // there); more is stretching and rejects the clip, unless fold_any_translation. Variations under
  // translation_noise × diameter are the export's float noise whatever the bone's length (a zero-length bone).
  double translation_tolerance = 0.01;
  double translation_bone_tolerance = 0.1;
  double translation_noise = 1e-4;
  bool fold_any_translation = false;
  UpAxis up = UpAxis::Auto;             // the file's up axis; Auto detects Z-up files
  int min_frames = 2;                   // clips shorter than this (after resampling) are rejected
  bool canonical_rest = true;           // re-express in the canonical rest; false keeps the file's rest pose and joint frames
};

// What preprocessing did to a clip, for the per-file report.
struct PreprocessReport {
  std::string file;
  std::vector<std::string> changes;  // one line per change, e.g. "merged dummy root 'joint_Root' into 'Hips'"
  std::string rejection;             // empty when accepted
  std::vector<std::string> warnings; // what the result may not show as the user expects (commands print them)

  bool accepted() const { return rejection.empty(); }
};

// How to undo the normalization: original = translate(rotate(scale * normalized)), in the file's own joint
// frames (reexpress_joint_frames with inverse_frames(rest_frames)).
struct Normalization {
  double scale = 1.0;               // original units per normalized unit (the diameter)
  Quat rotation = Quat::Identity(); // normalized frame -> original frame (up axis and heading)
  Vec3 origin = Vec3::Zero();       // original position of the normalized origin
  double source_fps = 30.0;         // frame rate of the file
  std::vector<Quat> rest_frames;    // (J) the file's joint frames -> canonical ones; empty: the file's frames kept
};

struct PreparedClip {
  Clip clip;                                // normalized; names are the file's own
  std::vector<std::string> canonical_names; // (J) canonical joint names
  Normalization normalization;
  PreprocessReport report;
};

PreparedClip preprocess(const Clip& raw, const std::string& file, const PreprocessOptions& options = {});
// Reads a motion file (read_clip: BVH, or an asset when registered) and preprocesses it; a file that preprocessing rejects
// throws nec::InputError naming the file and the reason.
PreparedClip preprocess_file(const std::string& path, const PreprocessOptions& options = {});

// Individual steps, usable on their own (each appends to `report`).
// Step 1: the root is a dummy outside the body (named like root/reference or
// with a single child far away) -> its child becomes the root.
void merge_dummy_root(Clip& clip, PreprocessReport& report);
// Step 2: folds non-root position channels into offsets (options' translation_*
// limits); returns false (and sets report.rejection) for one that stretches more.
bool fold_joint_translations(Clip& clip, const PreprocessOptions& options, PreprocessReport& report);
// Step 6: which file axis points up (Y or Z): Z only when the joints named
// foot/toe hang below the root along Z and not along Y; otherwise Y.
UpAxis detect_up_axis(const Clip& clip);
// Step 7: slerp/lerp resampling to `fps`.
Motion resample(const Motion& motion, double fps);

// Applies a rigid transform and scale to a whole clip: x -> rotation * (scale * x) + origin.
void transform_clip(Clip& clip, const Quat& rotation, double scale, const Vec3& origin);
// Undoes preprocess's scale, axes, heading and canonical rest (not the resampling): the file's units,
// offsets and joint frames.
Clip denormalize(const Clip& normalized, const Normalization& normalization);
// A clip normalized by `from`, put into the normalized frame of another clip of the same file frame (`to`):
// compares two files in one frame, e.g. a transfer onto its source's own skeleton with that source. Scale,
// axes and heading only: the joint frames stay `from`'s canonical ones (world positions do not depend on them).
Clip renormalize(const Clip& normalized, const Normalization& from, const Normalization& to);

// The decoder's side of step 6. Tokens hold no start heading (tat/model_space.h): this turns a decoded
// clip's body (turn_body: not its path) so that frame 0 faces +Z as preprocessing judges it, from the
// left and right joints, else towards the head (preprocessing tries the direction of travel between the
// two, which says nothing about the body here). `skeleton` is the normalized one the features are for.
// Returns the angle turned (radians about +Y); 0, turning nothing, when neither tells.
double face_forward_at_start(Features& features, const Skeleton& skeleton);

}  // namespace nec
