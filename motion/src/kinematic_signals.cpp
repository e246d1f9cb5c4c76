// Per-frame kinematic measurements of a motion: speeds, heading, posture and activity.
#include "nec/motion/kinematic_signals.h"

#include "nec/motion/kinematics.h"
#include "nec/motion/names.h"
#include "nec/motion/statistics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nec {
namespace {

// Centred difference of a per-frame series over `half` frames either side, per second.
template <typename Value, typename Get>
Value centred_rate(int frame, int frame_count, int half, double fps, Get get) {
  const int a = std::max(0, frame - half);
  const int b = std::min(frame_count - 1, frame + half);
  if (b <= a) return Value(get(a) - get(a));
  return (get(b) - get(a)) * (fps / (b - a));
}

// Joints that describe the body's layout: left/right pairs nearest the trunk,
// the head and the chest.
struct BodyLayout {
  std::vector<std::pair<int, int>> side_pairs;  // (left, right)
  int head = -1;
  int chest = -1;
};

BodyLayout find_body_layout(const Skeleton& skeleton) {
  BodyLayout layout;
  const int joint_count = skeleton.joint_count();
  std::vector<std::string> canonical(static_cast<size_t>(joint_count));
  std::vector<Side> sides(static_cast<size_t>(joint_count));
  for (int j = 0; j < joint_count; ++j) {
    canonical[j] = canonical_joint_name(skeleton.names[j]);
    sides[j] = joint_side(skeleton.names[j]);
  }
  // First sided joint of each limb: its parent has no side.
  const auto limb_start = [&](int j) { return skeleton.parents[j] < 0 || sides[skeleton.parents[j]] == Side::None; };
  // Each right limb pairs once: limbs with the same canonical name (the legs of a
  // spider) pair in file order, not all with the first right one (a diagonal).
  std::vector<bool> paired(joint_count, false);
  for (int left = 0; left < joint_count; ++left) {
    if (sides[left] != Side::Left || !limb_start(left)) continue;
    const std::string mirrored = mirrored_canonical_name(canonical[left]);
    for (int right = 0; right < joint_count; ++right) {
      if (!paired[right] && sides[right] == Side::Right && limb_start(right) && canonical[right] == mirrored) {
        layout.side_pairs.emplace_back(left, right);
        paired[right] = true;
        break;
      }
    }
  }
  for (int j = 1; j < joint_count; ++j) {
    bool is_head = false;
    for (const auto& word : split_joint_name(canonical[j])) is_head = is_head || word == "head";
    if (is_head && sides[j] == Side::None && (layout.head < 0 || skeleton.depth(j) < skeleton.depth(layout.head))) {
      layout.head = j;
    }
  }
  if (layout.head >= 0) {
    const auto children = skeleton.children_lists();
    for (int j : skeleton.path_to_root(layout.head)) {  // head first, root last
      if (j != 0 && children[j].size() >= 2) {
        layout.chest = j;
        break;
      }
    }
  }
  return layout;
}

Vec3 horizontal(Vec3 v) {
  v.y() = 0.0;
  return v;
}

// The head decides which way a body faces only where its horizontal distance to
// the root exceeds this many times the mean left-right width of the limb pairs.
constexpr double kHeadReachForFacing = 0.5;

// Facing direction (horizontal, not normalized) of every frame.
std::vector<Vec3> facing_directions(const Pose& pose, const BodyLayout& layout, std::string& source) {
  const int frame_count = pose.frame_count;
  std::vector<Vec3> facing(static_cast<size_t>(frame_count), Vec3::Zero());
  if (!layout.side_pairs.empty()) {
    source = "left/right joints";
    // Agreement with the head direction: negative means sides are swapped in the
    // names. Trusted only where the head sits clearly ahead of the root (a dog,
    // not an upright person, whose head may lean behind the hips).
    double agreement = 0.0, head_reach = 0.0, width = 0.0;
    for (int t = 0; t < frame_count; ++t) {
      Vec3 left = Vec3::Zero();
      for (const auto& [l, r] : layout.side_pairs) left += pose.position(t, l) - pose.position(t, r);
      facing[t] = Vec3(-left.z(), 0.0, left.x());  // left × up
      width += facing[t].norm() / static_cast<double>(layout.side_pairs.size());
      if (layout.head >= 0) {
        const Vec3 head = horizontal(pose.position(t, layout.head) - pose.position(t, 0));
        agreement += facing[t].dot(head);
        head_reach += head.norm();
      }
    }
    if (agreement < 0.0 && head_reach > kHeadReachForFacing * width) {
      for (auto& f : facing) f = -f;
    }
  } else if (layout.head >= 0) {
    source = "head";
    for (int t = 0; t < frame_count; ++t) facing[t] = horizontal(pose.position(t, layout.head) - pose.position(t, 0));
  } else {
    source = "root +Z axis";
    for (int t = 0; t < frame_count; ++t) facing[t] = horizontal(pose.rotation(t, 0) * Vec3::UnitZ());
  }
  return facing;
}

// Unwrapped heading in degrees; frames without a horizontal facing keep the previous heading.
std::vector<double> unwrapped_heading(const std::vector<Vec3>& facing) {
  std::vector<double> heading(facing.size(), 0.0);
  double previous = 0.0;
  bool have = false;
  for (size_t t = 0; t < facing.size(); ++t) {
    if (facing[t].norm() < 1e-9) {
      heading[t] = previous;
      continue;
    }
    const double angle = std::atan2(facing[t].x(), facing[t].z()) * kDegreesPerRadian;
    heading[t] = have ? previous + std::remainder(angle - previous, 360.0) : angle;
    previous = heading[t];
    have = true;
  }
  return heading;
}

Activity classify(const KinematicSignals& s, int t, const KinematicOptions& o, bool has_chest) {
  if (s.height_ratio[t] < o.low_height) {
    return has_chest && s.trunk_pitch[t] >= o.sit_pitch ? Activity::Sit : Activity::Lie;
  }
  const double speed = s.speed[t];
  if (speed < o.walk_speed) return Activity::Stand;
  if (speed < o.trot_speed) return Activity::Walk;
  if (speed < o.run_speed) return Activity::Trot;
  return Activity::Run;
}

}  // namespace

int frames_in(double seconds, double fps) { return std::max(1, static_cast<int>(std::lround(seconds * fps))); }

bool is_upright(Activity a) {
  return a == Activity::Stand || a == Activity::Walk || a == Activity::Trot || a == Activity::Run;
}
bool is_moving(Activity a) { return a == Activity::Walk || a == Activity::Trot || a == Activity::Run; }
bool is_low(Activity a) { return a == Activity::Lie || a == Activity::Sit; }

std::string_view activity_name(Activity activity) {
  switch (activity) {
    case Activity::Lie:
      return "lie";
    case Activity::Sit:
      return "sit";
    case Activity::Stand:
      return "stand";
    case Activity::Walk:
      return "walk";
    case Activity::Trot:
      return "trot";
    case Activity::Run:
      return "run";
    case Activity::Jump:
      return "jump";
  }
  return "?";
}

std::string_view turn_name(Turn turn) {
  switch (turn) {
    case Turn::Right:
      return "right";
    case Turn::None:
      return "none";
    case Turn::Left:
      return "left";
  }
  return "?";
}

void KinematicOptions::validate() const {
  const auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("KinematicOptions: ") + what);
  };
  require(standing_height >= 0.0, "standing_height must be >= 0 (0 = estimate)");
  require(standing_height_ratio > 0.0, "standing_height_ratio must be positive");
  require(walk_speed > 0.0 && walk_speed < trot_speed && trot_speed < run_speed,
          "speeds must satisfy 0 < walk_speed < trot_speed < run_speed");
  require(turn_rate > 0.0, "turn_rate must be positive");
  require(low_height > 0.0 && low_height < 1.0, "low_height must be in (0, 1)");
  require(jump_rise > 0.0 && airborne_height > 0.0, "jump_rise and airborne_height must be positive");
  require(still_joint_speed > 0.0, "still_joint_speed must be positive");
  require(velocity_window > 0.0 && turn_window > 0.0, "windows must be positive");
  require(contact_speed > 0.0, "contact_speed must be positive");
  require(min_jump_seconds > 0.0, "min_jump_seconds must be positive");
}

std::vector<double> measure_heading(const Clip& take) {
  if (take.motion.frame_count == 0) return {};
  std::string source;
  return unwrapped_heading(facing_directions(forward_kinematics(take.skeleton, take.motion),
                                             find_body_layout(take.skeleton), source));
}

KinematicSignals measure_kinematics(const Clip& take, const KinematicOptions& options) {
  options.validate();
  const Skeleton& skeleton = take.skeleton;
  const Motion& motion = take.motion;
  const int frame_count = motion.frame_count;
  const int joint_count = skeleton.joint_count();
  if (!(motion.fps > 0.0)) throw std::invalid_argument("measure_kinematics: the take's fps must be positive");
  KinematicSignals s;
  s.fps = motion.fps;
  s.body_size = skeleton.diameter() > 0.0 ? skeleton.diameter() : 1.0;
  if (frame_count == 0) return s;

  const Pose pose = forward_kinematics(skeleton, motion);
  const std::vector<Vec3> ends = end_site_positions(skeleton, pose);
  const int end_count = static_cast<int>(skeleton.end_sites.size());
  const BodyLayout layout = find_body_layout(skeleton);
  s.chest = layout.chest;
  const double body = s.body_size;
  const double fps = motion.fps;
  const auto root = [&](int t) -> const Vec3& { return pose.position(t, 0); };

  // Lowest point of the body, whether it rests on a support, and the floor
  // under the body: the support's height, or during a flight the lower of the
  // supports before and after it.
  const auto point = [&](int t, int i) -> const Vec3& {
    return i < joint_count ? pose.position(t, i) : ends[static_cast<size_t>(t) * end_count + (i - joint_count)];
  };
  std::vector<double> lowest(static_cast<size_t>(frame_count));
  std::vector<int> lowest_point(static_cast<size_t>(frame_count));
  for (int t = 0; t < frame_count; ++t) {
    int best = 0;
    for (int i = 1; i < joint_count + end_count; ++i) {
      if (point(t, i).y() < point(t, best).y()) best = i;
    }
    lowest_point[t] = best;
    lowest[t] = point(t, best).y();
  }
  std::vector<bool> contact(static_cast<size_t>(frame_count));
  for (int t = 0; t < frame_count; ++t) {
    const int i = lowest_point[t];
    const double speed = centred_rate<Vec3>(t, frame_count, 1, fps, [&](int u) { return point(u, i); }).norm() / body;
    contact[t] = speed < options.contact_speed;
  }
  std::vector<double> floor(lowest);
  std::vector<std::pair<int, int>> flights;  // frames [begin, end) without contact
  for (int t = 0; t < frame_count;) {
    if (contact[t]) {
      ++t;
      continue;
    }
    const int begin = t;
    while (t < frame_count && !contact[t]) ++t;
    flights.emplace_back(begin, t);
    const bool before = begin > 0;
    const bool after = t < frame_count;
    if (!before && !after) continue;
    const double level = before && after ? std::min(lowest[begin - 1], lowest[t])
                         : before        ? lowest[begin - 1]
                                         : lowest[t];
    for (int u = begin; u < t; ++u) floor[u] = std::min(level, lowest[u]);
  }

  // Horizontal velocity, heading and its rate.
  const std::vector<Vec3> facing = facing_directions(pose, layout, s.facing_source);
  s.heading = unwrapped_heading(facing);
  const int velocity_half = std::max(1, frames_in(options.velocity_window, fps) / 2);
  const int turn_half = std::max(1, frames_in(options.turn_window, fps) / 2);
  const int vertical_half = std::max(1, frames_in(0.1, fps) / 2);
  s.speed.resize(frame_count);
  s.forward_speed.resize(frame_count);
  s.lateral_speed.resize(frame_count);
  s.turn_rate.resize(frame_count);
  s.vertical_speed.resize(frame_count);
  for (int t = 0; t < frame_count; ++t) {
    const Vec3 velocity = centred_rate<Vec3>(t, frame_count, velocity_half, fps, [&](int i) { return root(i); }) / body;
    const Vec3 flat = horizontal(velocity);
    s.speed[t] = flat.norm();
    const double angle = s.heading[t] / kDegreesPerRadian;
    const Vec3 forward(std::sin(angle), 0.0, std::cos(angle));
    const Vec3 left(std::cos(angle), 0.0, -std::sin(angle));  // up × forward
    s.forward_speed[t] = flat.dot(forward);
    s.lateral_speed[t] = flat.dot(left);
    s.turn_rate[t] = centred_rate<double>(t, frame_count, turn_half, fps, [&](int i) { return s.heading[i]; });
    s.vertical_speed[t] =
        centred_rate<double>(t, frame_count, vertical_half, fps, [&](int i) { return root(i).y(); }) / body;
  }

  // Trunk pitch and joint speed.
  s.trunk_pitch.assign(frame_count, 0.0);
  s.joint_speed.assign(frame_count, 0.0);
  for (int t = 0; t < frame_count; ++t) {
    if (layout.chest >= 0) {
      const Vec3 trunk = pose.position(t, layout.chest) - root(t);
      const double length = trunk.norm();
      if (length > 1e-12) s.trunk_pitch[t] = std::asin(std::clamp(trunk.y() / length, -1.0, 1.0)) * kDegreesPerRadian;
    }
    if (frame_count > 1) {
      const int a = t + 1 < frame_count ? t : t - 1;
      double sum = 0.0;
      for (int j = 0; j < joint_count; ++j) sum += (pose.position(a + 1, j) - pose.position(a, j)).norm();
      s.joint_speed[t] = sum / joint_count * fps / body;
    }
  }

  // Standing height: the median root clearance while travelling, else an estimate from the body size.
  std::vector<double> clearance(static_cast<size_t>(frame_count));
  for (int t = 0; t < frame_count; ++t) clearance[t] = root(t).y() - lowest[t];
  if (options.standing_height > 0.0) {
    s.standing_height = options.standing_height;
    s.standing_height_source = "option";
  } else {
    std::vector<double> travelling;  // clearance while moving on the ground
    for (int t = 0; t < frame_count; ++t) {
      if (s.speed[t] >= options.walk_speed && contact[t]) {
        travelling.push_back(clearance[t]);
      }
    }
    if (static_cast<int>(travelling.size()) >= frames_in(1.0, fps)) {
      s.standing_height = upper_median(travelling);
      s.standing_height_source = "moving frames";
    } else {
      s.standing_height = std::max(options.standing_height_ratio * body, lower_quantile(clearance, 0.95));
      s.standing_height_source = "body size";
    }
    if (s.standing_height <= 0.0) s.standing_height = options.standing_height_ratio * body;
  }
  const double standing = s.standing_height;
  s.floor_height = floor;
  s.height_ratio.resize(frame_count);
  s.rise.resize(frame_count);
  s.lift.resize(frame_count);
  for (int t = 0; t < frame_count; ++t) {
    s.height_ratio[t] = clearance[t] / standing;
    s.rise[t] = (root(t).y() - floor[t] - standing) / standing;
    s.lift[t] = (lowest[t] - floor[t]) / standing;
  }

  // Jumps: flights long enough, high enough above the floor, with the root risen above the standing level.
  std::vector<bool> jumping(static_cast<size_t>(frame_count), false);
  const int min_jump = frames_in(options.min_jump_seconds, fps);
  for (const auto& [begin, end] : flights) {
    if (end - begin < min_jump) continue;
    const double lift = *std::max_element(s.lift.begin() + begin, s.lift.begin() + end);
    const double rise = *std::max_element(s.rise.begin() + begin, s.rise.begin() + end);
    if (lift >= options.airborne_height && rise >= options.jump_rise)
      std::fill(jumping.begin() + begin, jumping.begin() + end, true);
  }
  s.activity.resize(frame_count);
  s.turn.resize(frame_count);
  for (int t = 0; t < frame_count; ++t) {
    s.activity[t] = jumping[t] ? Activity::Jump : classify(s, t, options, layout.chest >= 0);
    const bool turning = is_upright(s.activity[t]) && std::abs(s.turn_rate[t]) >= options.turn_rate;
    s.turn[t] = !turning ? Turn::None : s.turn_rate[t] > 0 ? Turn::Left : Turn::Right;
  }
  return s;
}


}  // namespace nec
