// Side-view strips: camera choice from the motion's facing, framing over all
// frames, and drawing of bones, joints, ground and labels.
#include "nec/viewer/strip.h"

#include "nec/motion/kinematics.h"
#include "nec/motion/names.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace nec::viewer {
namespace {

constexpr double kDegreesPerRadian = 57.29577951308232;
const Rgb kBackground{255, 255, 255};
const Rgb kGroundFill{243, 243, 238};
const Rgb kGroundLine{150, 150, 150};
const Rgb kTick{178, 178, 178};
const Rgb kSeparator{222, 222, 222};
const Rgb kLabel{105, 105, 105};
const Rgb kCenterBone{62, 68, 82};
const Rgb kLeftBone{45, 105, 215};
const Rgb kRightBone{215, 80, 45};

Vec3 heading_direction(double degrees) {
  const double radians = degrees / kDegreesPerRadian;
  return {std::sin(radians), 0.0, std::cos(radians)};
}

Vec3 horizontal(const Vec3& v) { return {v.x(), 0.0, v.z()}; }

// Per-frame horizontal facing of a +Y-up clip, and how it was found: from the
// joints on the left and right (forward = left x up, left = mean left joint -
// mean right joint), else from the root's travel over the clip, else from the
// root's +Z axis. Zero vectors where a frame has no horizontal facing.
std::vector<Vec3> facing_directions(const Clip& upright, const Pose& pose, std::string& source) {
  const Skeleton& skeleton = upright.skeleton;
  std::vector<int> left, right;
  for (int j = 0; j < skeleton.joint_count(); ++j) {
    const Side side = joint_side(skeleton.names[j]);
    if (side == Side::Left) left.push_back(j);
    if (side == Side::Right) right.push_back(j);
  }
  const int frame_count = pose.frame_count;
  std::vector<Vec3> facing(frame_count, Vec3::Zero());
  if (!left.empty() && !right.empty()) {
    source = "left/right joints";
    for (int t = 0; t < frame_count; ++t) {
      Vec3 side = Vec3::Zero();
      for (int j : left) side += pose.position(t, j) / static_cast<double>(left.size());
      for (int j : right) side -= pose.position(t, j) / static_cast<double>(right.size());
      facing[t] = horizontal(side.cross(Vec3::UnitY()));
    }
    return facing;
  }
  const Vec3 travel = horizontal(pose.position(frame_count - 1, 0) - pose.position(0, 0));
  if (travel.norm() > 0.5 * skeleton.diameter()) {
    source = "root travel";
    std::fill(facing.begin(), facing.end(), travel);
    return facing;
  }
  source = "root +Z axis";
  for (int t = 0; t < frame_count; ++t) facing[t] = horizontal(pose.rotation(t, 0) * Vec3::UnitZ());
  return facing;
}

// The forward direction: the mean facing over the clip taken as an axis (mean
// of doubled angles), so that a clip walking out and back still gets a side
// view, signed like the first frame with a facing.
Vec3 choose_forward(const Clip& upright, const Pose& pose, const StripOptions& options, std::string& source) {
  if (options.facing_degrees) {
    source = "option";
    return heading_direction(*options.facing_degrees);
  }
  const std::vector<Vec3> facing = facing_directions(upright, pose, source);
  double c = 0.0, s = 0.0;
  int counted = 0;
  Vec3 first = Vec3::Zero();
  for (const Vec3& f : facing) {
    if (f.norm() < 1e-12) continue;
    if (counted++ == 0) first = f.normalized();
    const double angle = std::atan2(f.x(), f.z());
    c += std::cos(2.0 * angle);
    s += std::sin(2.0 * angle);
  }
  if (counted == 0) {
    source = "default +Z";
    return Vec3::UnitZ();
  }
  if (std::hypot(c, s) / counted < 0.2) {  // faces every way in turn: use where it starts
    source += ", first frame";
    return first;
  }
  Vec3 axis = heading_direction(std::atan2(s, c) / 2.0 * kDegreesPerRadian);
  if (axis.dot(first) < 0.0) axis = -axis;
  source += ", mean over the clip";
  return axis;
}

// 1, 2 or 5 times a power of ten, close to `value`.
double nice_step(double value) {
  if (!(value > 0.0) || !std::isfinite(value)) return 1.0;
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  const double m = value / power;
  return (m < 1.5 ? 1.0 : m < 3.5 ? 2.0 : m < 7.5 ? 5.0 : 10.0) * power;
}

Rgb bone_color(const std::string& name) {
  switch (joint_side(name)) {
    case Side::Left:
      return kLeftBone;
    case Side::Right:
      return kRightBone;
    case Side::None:
      break;
  }
  return kCenterBone;
}

std::string frame_label(int frame, double fps) {
  char text[64];
  std::snprintf(text, sizeof(text), "frame %d  %.2f s", frame, fps > 0.0 ? frame / fps : 0.0);
  return text;
}

}  // namespace

void StripOptions::validate() const {
  if (frames < 1 || frames > 1000) throw std::invalid_argument("strip frames must be in 1..1000, got " + std::to_string(frames));
  if (panel_height < 32 || panel_height > 4096) {
    throw std::invalid_argument("strip panel height must be in 32..4096 pixels, got " + std::to_string(panel_height));
  }
  if (facing_degrees && !std::isfinite(*facing_degrees)) throw std::invalid_argument("strip facing must be finite");
}

Point StripView::project(int panel, const Vec3& position) const {
  const Vec3 p = up_rotation * position;
  const double along = p.dot(forward) - panel_root[panel] - center_offset;
  return {panel * panel_width + 0.5 * panel_width + along * pixels_per_unit,
          ground_row - (p.y() - ground_height) * pixels_per_unit};
}

double StripView::depth(const Vec3& position) const { return (up_rotation * position).dot(away); }

StripView plan_strip(const Clip& clip, const StripOptions& options) {
  options.validate();
  const int frame_count = clip.motion.frame_count;
  if (frame_count < 1) throw std::invalid_argument("cannot draw a strip of a motion without frames");
  StripView view;
  const UpAxis up = options.up == UpAxis::Auto ? detect_up_axis(clip) : options.up;
  if (up == UpAxis::Z) view.up_rotation = axis_rotation(0, -90.0);  // file +Z -> +Y
  Clip upright = clip;
  transform_clip(upright, view.up_rotation, 1.0, Vec3::Zero());

  const int k = options.frames;
  for (int i = 0; i < k; ++i) {
    view.frames.push_back(k == 1 ? (frame_count - 1) / 2
                                 : static_cast<int>(std::lround(static_cast<double>(i) * (frame_count - 1) / (k - 1))));
  }

  // Extent of the pose relative to the root (along forward) and of the height, over every frame.
  const Pose pose = forward_kinematics(upright.skeleton, upright.motion);
  view.forward = choose_forward(upright, pose, options, view.facing_source);
  view.away = Vec3::UnitY().cross(view.forward);
  const std::vector<Vec3> sites = end_site_positions(upright.skeleton, pose);
  const size_t site_count = upright.skeleton.end_sites.size();
  double along_min = std::numeric_limits<double>::max(), along_max = -along_min;
  double low = along_min, high = -along_min;
  for (int t = 0; t < frame_count; ++t) {
    const double root = pose.position(t, 0).dot(view.forward);
    const auto include = [&](const Vec3& p) {
      const double along = p.dot(view.forward) - root;
      along_min = std::min(along_min, along);
      along_max = std::max(along_max, along);
      low = std::min(low, p.y());
      high = std::max(high, p.y());
    };
    for (int j = 0; j < pose.joint_count; ++j) include(pose.position(t, j));
    for (size_t e = 0; e < site_count; ++e) include(sites[t * site_count + e]);
  }
  for (int frame : view.frames) view.panel_root.push_back(pose.position(frame, 0).dot(view.forward));
  view.center_offset = 0.5 * (along_min + along_max);
  view.ground_height = low;

  const double floor_extent = 1e-6 * std::max(1.0, upright.skeleton.diameter());
  const double width_extent = std::max(along_max - along_min, floor_extent);
  const double height_extent = std::max(high - low, floor_extent);
  const int h = options.panel_height;
  const int margin = std::max(4, static_cast<int>(std::lround(0.05 * h)));
  view.label_scale = options.labels ? std::max(1, static_cast<int>(std::lround(h / 160.0))) : 0;
  const int top = margin + (options.labels ? 7 * view.label_scale + margin : 0);
  view.panel_height = h;
  view.ground_row = h - std::max(margin, static_cast<int>(std::lround(0.1 * h)));
  const double vertical_scale = (view.ground_row - top) / height_extent;
  const int label_width = options.labels ? text_width(frame_label(frame_count - 1, clip.motion.fps), view.label_scale) : 0;
  const double wanted = width_extent * vertical_scale + 2.0 * margin;
  view.panel_width = static_cast<int>(std::lround(std::clamp(wanted, 0.5 * h, 2.0 * h)));
  view.panel_width = std::max(view.panel_width, label_width + 2 * margin);
  const double horizontal_scale = (view.panel_width - 2.0 * margin) / width_extent;
  view.pixels_per_unit = std::min(vertical_scale, horizontal_scale);
  view.tick_spacing = nice_step(std::max(width_extent, height_extent) / 3.0);
  return view;
}

Image draw_strip(const Clip& clip, const StripView& view) {
  const Skeleton& skeleton = clip.skeleton;
  Image image(view.width(), view.panel_height, kBackground);
  const Pose pose = forward_kinematics(skeleton, clip.motion);
  const std::vector<Vec3> sites = end_site_positions(skeleton, pose);
  const size_t site_count = skeleton.end_sites.size();
  const double radius = std::max(1.1, view.panel_height / 150.0);  // bone half-width, pixels
  const int margin = std::max(4, static_cast<int>(std::lround(0.05 * view.panel_height)));

  struct Bone {
    Vec3 from, to;
    Rgb color;
    bool to_joint;  // ends at a joint (gets a dot) rather than an end site
  };
  for (size_t panel = 0; panel < view.frames.size(); ++panel) {
    const int p = static_cast<int>(panel);
    const int t = view.frames[panel];
    const int left = p * view.panel_width;
    Image canvas(view.panel_width, view.panel_height, kBackground);  // clips the drawing to the panel
    const auto local = [&](const Vec3& position) {
      Point pixel = view.project(p, position);
      pixel.x() -= left;
      return pixel;
    };

    fill_rect(canvas, 0, view.ground_row, view.panel_width, view.panel_height, kGroundFill);
    const double root = view.panel_root[panel];
    const double first_tick = std::ceil((root + view.center_offset - 0.5 * view.panel_width / view.pixels_per_unit) /
                                        view.tick_spacing);
    for (double n = first_tick;; n += 1.0) {
      const double x = 0.5 * view.panel_width + (n * view.tick_spacing - root - view.center_offset) * view.pixels_per_unit;
      if (x > view.panel_width + 1.0) break;
      draw_segment(canvas, {x, view.ground_row + 0.0}, {x, view.ground_row + 0.35 * margin + 3.0}, 0.6, kTick);
    }
    draw_segment(canvas, {0.0, view.ground_row + 0.0}, {view.panel_width + 0.0, view.ground_row + 0.0}, 0.7, kGroundLine);

    std::vector<Bone> bones;
    for (int j = 1; j < skeleton.joint_count(); ++j) {
      bones.push_back({pose.position(t, skeleton.parents[j]), pose.position(t, j), bone_color(skeleton.names[j]), true});
    }
    for (size_t e = 0; e < site_count; ++e) {
      const int parent = skeleton.end_sites[e].parent;
      bones.push_back({pose.position(t, parent), sites[t * site_count + e], bone_color(skeleton.names[parent]), false});
    }
    double near = std::numeric_limits<double>::max(), far = -near;
    for (int j = 0; j < skeleton.joint_count(); ++j) {
      near = std::min(near, view.depth(pose.position(t, j)));
      far = std::max(far, view.depth(pose.position(t, j)));
    }
    // Up to 55 % towards the background for the farthest bones; depth differences
    // under a quarter of the body size count as partly flat, so a front view stays even.
    const double depth_range = std::max(far - near, 0.25 * skeleton.diameter());
    const auto paleness = [&](double depth) { return depth_range > 0.0 ? 0.55 * (depth - near) / depth_range : 0.0; };
    std::stable_sort(bones.begin(), bones.end(), [&](const Bone& a, const Bone& b) {
      return view.depth(a.from + a.to) > view.depth(b.from + b.to);
    });
    for (const Bone& bone : bones) {
      const Rgb color = mix(bone.color, kBackground, paleness(0.5 * view.depth(bone.from + bone.to)));
      draw_segment(canvas, local(bone.from), local(bone.to), radius, color);
      if (bone.to_joint) {
        draw_disc(canvas, local(bone.to), 1.5 * radius, mix(color, {0, 0, 0}, 0.25));
      }
    }
    draw_disc(canvas, local(pose.position(t, 0)), 2.0 * radius, mix(kCenterBone, {0, 0, 0}, 0.25));
    if (view.label_scale > 0) {
      draw_text(canvas, margin, margin, frame_label(t, clip.motion.fps), view.label_scale, kLabel);
    }
    for (int y = 0; y < view.panel_height; ++y) {
      for (int x = 0; x < view.panel_width; ++x) image.at(left + x, y) = canvas.at(x, y);
    }
    if (panel > 0) fill_rect(image, left, 0, left + 1, view.panel_height, kSeparator);
  }
  return image;
}

Image render_strip(const Clip& clip, const StripOptions& options) { return draw_strip(clip, plan_strip(clip, options)); }

Image stack_rows(const std::vector<Image>& rows) {
  int width = 0, height = 0;
  for (const Image& row : rows) {
    width = std::max(width, row.width);
    height += row.height;
  }
  Image out(width, height, kBackground);
  int top = 0;
  for (const Image& row : rows) {
    for (int y = 0; y < row.height; ++y) {
      for (int x = 0; x < row.width; ++x) out.at(x, top + y) = row.at(x, y);
    }
    top += row.height;
  }
  return out;
}

}  // namespace nec::viewer
