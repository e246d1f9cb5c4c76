// Self-contained HTML pages that play BVH clips side by side in three.js.
//
//   std::vector<ViewClip> clips = {load_view_clip("walk.bvh"), load_view_clip("dog.bvh")};
//   write_file_atomic("view.html", make_view_html(clips, ViewOptions{}));
//
// The page holds everything it needs and opens from file:// without network:
// each clip as BVH text (written by nec's BVH writer, +Y up), a rigged asset's
// GLB (its skinned mesh moves with the bones), three.js with its BVHLoader,
// GLTFLoader and OrbitControls (embedded into nec at build time, see
// viewer/CMakeLists.txt), and the player (viewer/assets/view.js): skeletons
// with bones, play/pause, scrub, speed, orbit camera, the (first) caption
// under each clip and a ground grid. Every clip is scaled to the same body
// size and gets its own lane; `view.html#t=2.5` opens paused at 2.5 s. Joints
// are placed as nec's forward kinematics places them (position channels
// replace the offset, unlike three.js's own BVH playback); the page checks this
// against positions nec computed. It reports what it loaded in <pre id="nec-status">
// ({"ok", "state", "clips": [{"name", "joints", "end_sites", "frames", ...}],
// "errors", "warnings", "visible"}) for scripts and tests.
#pragma once

#include "nec/motion/motion.h"
#include "nec/corpus/preprocess.h"

#include <stdexcept>
#include <string>
#include <vector>

namespace nec::viewer {

struct ViewClip {
  std::string name;                   // shown above the caption, e.g. "01_01"
  std::vector<std::string> captions;  // shown under the skeleton, one line each; may be empty
  Clip clip;
  std::string mesh_glb{};             // a GLB whose first animation is `clip`: its skinned mesh is shown moving; may be empty
};

struct ViewOptions {
  std::string title = "nec view";  // page title and heading
  UpAxis up = UpAxis::Auto;        // up axis of the clips; Auto detects Z-up files clip by clip
  double max_fps = 0.0;            // clips faster than this are resampled to it, e.g. 30 (smaller pages); 0 keeps every rate

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

// three.js was not embedded at build time.
class ViewerUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads a motion file (read_clip; InputError on bad input); the name is the
// file name without extension and the captions those of nec::captions_for (the
// `clip.txt` sidecar next to the file, else the Bandai labels). A rigged asset
// also gets mesh_glb (when a GLB writer is registered: motion/clip_file.h).
ViewClip load_view_clip(const std::string& path);

// Whether three.js was embedded into this build, and its npm version ("" when not).
bool have_three();
std::string three_version();

// The page. Throws ViewerUnavailable without three.js (the message says to
// run scripts/setup.sh), std::invalid_argument for no clips, a clip without
// frames or bad options.
std::string make_view_html(const std::vector<ViewClip>& clips, const ViewOptions& options = {});

// The page of `nec serve` (viewer/assets/studio.html): pick or upload a rig, captions on a timeline, generate,
// transfer, search; each result shown in a make_view_html page the server makes. Needs no three.js of its own.
std::string make_studio_html();

}  // namespace nec::viewer
