// Strips of evenly spaced frames of a motion, drawn from the side, for
// READMEs and reports.
//
//   Clip clip = read_bvh("walk.bvh");
//   StripOptions options;                       // 6 panels, 320 px high
//   write_png("walk.png", render_strip(clip, options));
//
// Camera: orthographic, looking horizontally at the creature's right side so
// that its forward direction points right. Forward is the mean facing over
// the clip, taken as an axis so that walking back and forth still gives a side
// view, and signed like frame 0. The facing comes from the joints named as
// left and right (forward = left x up; nec::joint_side), else from the root's
// travel, else from the root's +Z axis. Each panel follows the root along the forward direction;
// ticks on the ground line stay fixed in the world, so travel shows as ticks
// sliding left. One scale for all panels: the pose relative to the root fits
// in every panel for every frame of the clip (not only the frames shown), and
// the ground line is the lowest point of the whole motion.
// Bones on the creature's left are blue, right red, others dark; far bones
// are drawn first and paler.
#pragma once

#include "nec/motion/motion.h"
#include "nec/corpus/preprocess.h"
#include "nec/viewer/raster.h"

#include <optional>
#include <string>
#include <vector>

namespace nec::viewer {

struct StripOptions {
  int frames = 6;                        // panels, evenly spaced from the first frame to the last (1: the middle one)
  int panel_height = 320;                // pixels, e.g. 320; panel widths follow the motion's aspect (0.5x to 2x)
  bool labels = true;                    // "frame 120  1.00 s" at the top of each panel
  UpAxis up = UpAxis::Auto;              // the file's up axis; Auto detects Z-up files
  std::optional<double> facing_degrees;  // forward heading about +Y (0 = +Z, 90 = +X); unset: from the motion

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

// The camera and pixel layout of one strip (one row of panels).
struct StripView {
  Quat up_rotation = Quat::Identity();  // file axes -> +Y up
  Vec3 forward = Vec3::UnitZ();         // horizontal, drawn pointing right (after up_rotation)
  Vec3 away = Vec3::UnitX();            // horizontal, from the camera into the picture: up x forward
  std::string facing_source;            // how forward was chosen, e.g. "left/right joints, mean over the clip"
  std::vector<int> frames;              // (K) frame shown in each panel
  std::vector<double> panel_root;       // (K) root position along forward in each panel (the panel follows it)
  double center_offset = 0.0;           // along forward, relative to the root, drawn at the panel centre
  double ground_height = 0.0;           // lowest height of the motion, file units
  double pixels_per_unit = 1.0;         // file units -> pixels
  double tick_spacing = 1.0;            // file units between ground ticks: a third of the larger extent, rounded
  int panel_width = 0;                  // pixels
  int panel_height = 0;                 // pixels
  int ground_row = 0;                   // pixel row of the ground line
  int label_scale = 1;                  // font pixel size of the labels; 0 without labels

  int width() const { return panel_width * static_cast<int>(frames.size()); }
  // Pixel of a position (file coordinates, as forward_kinematics gives them) in panel `panel`.
  Point project(int panel, const Vec3& position) const;
  // Distance along `away` (file coordinates): larger is farther from the camera.
  double depth(const Vec3& position) const;
};

// Throws std::invalid_argument for bad options or a clip without frames.
StripView plan_strip(const Clip& clip, const StripOptions& options);
Image draw_strip(const Clip& clip, const StripView& view);
Image render_strip(const Clip& clip, const StripOptions& options);
// Rows top to bottom, left-aligned on a white background.
Image stack_rows(const std::vector<Image>& rows);

}  // namespace nec::viewer
