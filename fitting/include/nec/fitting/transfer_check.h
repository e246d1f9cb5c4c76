// What can be checked without a human when a motion is moved onto another
// skeleton (`nec transfer`): does the target travel as fast as the source
// relative to its own size, turn as much, head the same way, put its feet down
// in a rhythm, and keep its bones at their lengths?
//
//   const Clip source = preprocess(read_bvh("human_walk.bvh"), "human_walk.bvh").clip;
//   const Clip output = preprocess(read_bvh("dog_walk.bvh"), "dog_walk.bvh").clip;
//   TransferCheck check = check_transfer(source, output);
//   check.speed_ratio;            // 1: as many body sizes per second as the source
//   check.output.gait.touchdowns_per_second;  // > 0: feet are put down
//
// Both clips are expected with +Y up, as `preprocess` leaves them. Sizes are Skeleton::diameter() ("body sizes"), whatever the units.
#pragma once

#include "nec/motion/motion.h"

#include <vector>

namespace nec {

struct GaitMeasurements {
  int feet = 0;                       // leaf joints that spend time near the ground
  double contact_fraction = 0.0;      // share of (frame, foot) pairs with the foot planted
  double touchdowns_per_second = 0.0; // foot plants (of all feet together) per second
  // touchdowns_per_second / feet: the steps a foot takes per second (its cadence), which a transfer onto more
  // or fewer legs can keep where the total cannot.
  double touchdowns_per_foot_second = 0.0;
  // Foot skate: mean horizontal speed (body sizes/s) of leaf joints over the frames they spend below
  // kContactHeight, however fast they move there; NaN if none comes down that low.
  double skate = 0.0;
};

struct MotionMeasurements {
  double seconds = 0.0;
  double speed = 0.0;           // mean horizontal root speed, body sizes/s
  double distance = 0.0;        // net horizontal root displacement, body sizes
  double heading_change = 0.0;  // degrees, + = left (counter-clockwise seen from +Y)
  // Degrees from the mean facing to the net root displacement: 0 forward, 90 to
  // the left, 180 backward; NaN if the displacement is under kMinTravel.
  double travel_direction = 0.0;
  GaitMeasurements gait;
  // The lowest joint's height above the file's ground (y = 0) in each kFloorWindowSeconds window (the last
  // one may be shorter), body sizes: where the body stands, window by window.
  std::vector<double> lowest_heights;
  double bone_length_change = 0.0;  // largest |bone length - rest length| over frames and bones, body sizes
};

// Under this net displacement (body sizes) a clip has no direction of travel.
inline constexpr double kMinTravel = 0.1;

// Foot contact: a leaf joint below kContactHeight body sizes above the floor (the
// lowest point the clip's joints reach) moving slower than kContactSpeed body
// sizes per second; a plant must last two frames to count.
inline constexpr double kContactHeight = 0.04;
inline constexpr double kContactSpeed = 0.3;

// The contact rule per frame for one leaf joint, from positions (T, J) as joint_positions writes them; `floor`
// is the clip's lowest joint height, `size` its body size.
std::vector<bool> contact_frames(const std::vector<Vec3>& positions, int joints, int leaf, double floor, double size,
                                 double fps);
// Frames where a plant starts: in contact there and in the next frame, not in the frame before (a foot already
// down at the first frame has not touched down).
std::vector<int> touchdown_frames(const std::vector<bool>& contact);

// Window length of MotionMeasurements::lowest_heights, and how far (body sizes) a transfer's lowest joint may
// sit from where its source's does, window by window, to stand on the floor as the source does (about 5 cm
// on a person).
inline constexpr double kFloorWindowSeconds = 1.0;
inline constexpr double kFloorTolerance = 0.03;

// Throws std::invalid_argument for a clip without frames or with fps <= 0.
MotionMeasurements measure_motion(const Clip& clip);

struct TransferCheck {
  MotionMeasurements source, output;
  double speed_ratio = 0.0;          // output.speed / source.speed; NaN if the source stands still
  double heading_difference = 0.0;   // output - source heading change, degrees
  double direction_difference = 0.0; // output - source travel direction, degrees in (-180, 180]; NaN if either has none
  // Mean distance between the two clips' joints over frames, root trajectory included, in the source's body
  // sizes: only when both have the same skeleton (joint names in the same order) and frame count, as a
  // transfer onto the source's own skeleton does; NaN otherwise.
  double joint_distance = 0.0;
  // The largest |output - source| lowest height over the windows both clips have, body sizes (each its own):
  // a transfer that floats above, or sinks into, the floor its source stands on; NaN if either has none.
  double floor_difference = 0.0;
};

TransferCheck check_transfer(const Clip& source, const Clip& output);

}  // namespace nec
