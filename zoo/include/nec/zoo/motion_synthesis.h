// Procedural motion for zoo creatures: gaits with planted feet, turns,
// start/stop, idle breathing, sit / lie down, jump, attack, wing flap, glide,
// take-off, flight, swimming and slithering, all from one MotionSpec.
//
//   Creature spider = make_creature(BodyPlan::Spider, /*seed=*/7);
//   MotionSpec spec;
//   spec.action = Action::Walk;
//   spec.speed = 0.8;        // body lengths per second
//   spec.turn_rate = 30.0;   // degrees per second, + = left
//   SynthesizedMotion out = synthesize_motion(spider, spec);
//   write_bvh("spider_walk.bvh", spider.skeleton, out.motion);
//
// How it works. The root trajectory is integrated from the speed and turn
// rate (with ramps for start/stop). The body (root, spine, neck, head, tail,
// wings, fins, arms) is posed per frame; then every leg gets stance intervals
// from its gait phase (or the action's schedule). A stance foot is planted at
// the point under its hip at mid-stance and stays fixed in world space; a
// swing foot follows an arc to its next stance point. Leg joint rotations come
// from inverse kinematics (analytic for two bones, FABRIK for longer chains)
// converted to local rotations relative to each bone's REST direction, so any
// rest pose (T-pose, A-pose, crouched) works. The root is lowered where a
// stance leg could not reach its foot otherwise (raised where it would have
// to fold more than it can). Arms and wings are posed by bone directions in
// the body's frame, so they too ignore the rest pose. Tails, necks and
// antennae follow with a phase lag.
//
// Conventions (those of creature.h): +Y up, the creature faces +Z with
// identity rotations, its left is +X, the ground is y = 0. A positive turn
// rate turns left: counter-clockwise seen from above (+Y).
#pragma once

#include "nec/motion/random.h"

#include "nec/zoo/creature.h"

#include <cstdint>
#include <string_view>
#include <vector>

namespace nec::zoo {

enum class Action {
  Idle,       // stands and breathes, looks around
  Walk,       // slowest gait (biped alternating, quadruped four-beat, hexapod tripod, spider/centipede wave)
  Trot,       // quadrupeds: diagonal pairs
  Run,        // bipeds, birds, insects, spiders, centipedes: fast gait
  Gallop,     // quadrupeds: transverse gallop with a flight phase
  Turn,       // turns on the spot, stepping
  Jump,       // crouch, take off, fly ballistically, land (forward or in place)
  Sit,        // sits down and stays
  LieDown,    // lowers the body to the ground and stays
  Attack,     // plan-specific strike: punch, lunge and bite, rear and strike, snake strike, peck, dart
  Slither,    // snakes: lateral undulation along the path
  Swim,       // fish: body wave with the tail, root moving forward
  Fly,        // winged plans: flapping flight at altitude
  Glide,      // winged plans: wings spread, slowly descending
  TakeOff,    // winged plans: from standing to climbing flight
  FlapWings,  // winged plans: stands and beats its wings
  // Gestures of bipeds (arms and a leg), standing in place:
  Wave,        // raises a hand (side) or both (Side::None) and waves it from side to side
  RaiseHands,  // raises a hand (side) or both (Side::None) above the head and holds it there
  Point,       // points straight ahead with one arm (side)
  Clap,        // claps both hands in front of the chest
  Bow,         // bends forward at the hips and straightens again
  Crouch,      // bends the knees and lowers the body, then stays low
  Kick,        // kicks forward with one leg (side), the arms out for balance
  Eat,         // four-legged plans: lowers its head to the ground (the body tipping forward when the neck is
               // short), grazes and chews, and looks up again
  Shake,       // four-legged plans and birds: shakes itself off, the body rolling fast from side to side
  JumpingJacks,  // bipeds: hops the feet apart and together, the arms swinging up over the head and down
  Stretch,     // bipeds: reaches both arms up over the head, leans to one side and the other, lowers them
  Dance,       // bipeds: steps from foot to foot to a beat, swaying and bouncing, the arms swinging
  GetUp,       // every plan that sits or lies down: lying (or, without LieDown, sitting) at first, then gets up
               // and stands: that action played backwards
};

constexpr Action kAllActions[] = {Action::Idle,  Action::Walk,    Action::Trot,   Action::Run,     Action::Gallop,
                                  Action::Turn,  Action::Jump,    Action::Sit,    Action::LieDown, Action::Attack,
                                  Action::Slither, Action::Swim,  Action::Fly,    Action::Glide,   Action::TakeOff,
                                  Action::FlapWings, Action::Wave, Action::RaiseHands, Action::Point, Action::Clap,
                                  Action::Bow,   Action::Crouch,  Action::Kick,   Action::Eat,     Action::Shake,
                                  Action::JumpingJacks, Action::Stretch, Action::Dance, Action::GetUp};

std::string_view action_name(Action action);  // "idle", "walk", ..., "lie_down", "take_off", "raise_hands"
// Parses a name as printed by action_name; false when unknown.
bool parse_action(std::string_view name, Action& action);

// Whether speed and turn rate apply (the creature travels or turns).
bool is_locomotion(Action action);
// Whether the action is a legged gait with a phase pattern (walk, trot, run, gallop, turn).
bool is_gait(Action action);

// Actions a body plan supports (get_up too wherever sit or lie_down is), in kAllActions order:
//   biped      idle walk run turn jump sit attack wave raise_hands point clap bow crouch kick jumping_jacks
//              stretch dance
//   quadruped  idle walk trot gallop turn jump sit lie_down attack eat shake
//   hexapod    idle walk run turn jump lie_down attack
//   spider     idle walk run turn jump lie_down attack
//   snake      idle attack slither
//   bird       idle walk run jump sit attack fly glide take_off flap_wings shake
//   fish       idle attack swim
//   dragon     idle walk trot gallop turn sit lie_down attack fly glide take_off flap_wings eat shake
//   centipede  idle walk run attack
//   crab       idle walk run turn lie_down attack
//   ungulate   idle walk trot gallop turn jump lie_down eat shake
//   elephant   idle walk trot turn lie_down attack
//   ground_bird idle walk run jump sit attack flap_wings shake
//   hopper     idle walk run jump sit               (walk and run hop with both feet)
//   dinosaur   idle walk run sit attack
//   primate    idle walk gallop turn sit attack              (walks on its knuckles)
std::vector<Action> supported_actions(BodyPlan plan);
bool supports_action(BodyPlan plan, Action action);
// The action GetUp plays backwards on a plan: LieDown where it has it, else Sit.
Action lowering_action(BodyPlan plan);

// How a creature carries itself while it moves or stands (locomotion, turning on the spot and idling only).
enum class Manner {
  Neutral,
  Tired,      // head and trunk low, small steps, limp arm swing, heavy breathing
  Energetic,  // high steps, big arm swing, a bounce in the stride
  Cautious,   // body lowered, head forward and low, short steps, looking around
  Proud,      // chest and head up, a fuller stride
};
constexpr Manner kAllManners[] = {Manner::Neutral, Manner::Tired, Manner::Energetic, Manner::Cautious, Manner::Proud};
std::string_view manner_name(Manner manner);  // "neutral", "tired", "energetic", "cautious", "proud"
bool parse_manner(std::string_view name, Manner& manner);
// Whether an action takes a manner (the others are made Neutral).
bool takes_manner(Action action);

struct MotionSpec {
  Action action = Action::Walk;
  double speed = 0.5;             // body lengths per second along the heading, e.g. 0.8; locomotion, Jump (0 = in place), TakeOff
  double turn_rate = 0.0;         // degrees per second, + = left (counter-clockwise seen from +Y); locomotion only
  double direction = 0.0;         // Walk, Run: degrees of travel from the facing, + = left: 180 backs up, 90 / -90
                                  // sidestep to the left / right (then straight, at most 0.8 x the typical speed)
  bool start_from_still = false;  // locomotion: stands still first, then accelerates
  bool stop_at_end = false;       // locomotion: decelerates and stands still at the end
  double seconds = 4.0;           // clip length, e.g. 4
  double fps = 30.0;              // frames per second, e.g. 30
  Manner manner = Manner::Neutral; // posture and amplitude while moving or standing; see takes_manner
  Side side = Side::None;         // Attack, Point, Kick: striking side (arm, lunge direction, leg); None = chosen
                                  // from seed. Wave, RaiseHands: the hand; None = both
  uint64_t seed = 0;              // small style variations: step height, breathing rate, head motion

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

// Speeds in body lengths per second (Creature::body_length) for an action.
// typical_speed is what the plain verb means ("walks"): speed words are
// relative to it. max_speed is the most synthesize_motion produces (the legs'
// reach and cadence); 0 for actions without travel.
double typical_speed(const Creature& creature, Action action);
double max_speed(const Creature& creature, Action action);
// Most turn rate (degrees per second) the legs can follow at `speed`; large for legless plans.
double max_turn_rate(const Creature& creature, Action action, double speed);

enum class SpeedClass { Slow, Normal, Fast };
constexpr double kSlowSpeedRatio = 0.7;  // below 0.7 x typical: slow
constexpr double kFastSpeedRatio = 1.4;  // above 1.4 x typical: fast
SpeedClass classify_speed(double speed, double typical);

// Share of the full speed (0..1) at time t of a locomotion clip: ramps up
// after a still start and down before a stop. Turn rate scales the same way.
double travel_ramp(const MotionSpec& spec, double t);
// Heading change over the whole clip, degrees (+ = left): the integral of the turn rate.
double heading_change_degrees(const MotionSpec& spec);

// The phase pattern of a gait. With the gait clock c(t) = frequency * t, leg i
// (Creature::limbs of kind Leg, in order) is at phase frac(c + phases[i]): it
// touches down at phase 0, stays planted while the phase is below
// duty_factor and swings for the rest of the cycle. Legs with equal phases
// move together; a smaller phase touches down later.
struct GaitPattern {
  std::vector<double> phases;  // (legs) e.g. biped walk {0, 0.5}
  double duty_factor = 1.0;    // stance share of the cycle, e.g. 0.6
};
// Empty phases for actions without a gait.
GaitPattern gait_pattern(const Creature& creature, Action action);

struct LegTrack {
  int limb = 0;                 // index into Creature::limbs
  std::vector<uint8_t> stance;  // (T) 1 while the foot is planted on the ground
};

struct SynthesizedMotion {
  Motion motion;                // (T, J) on creature.skeleton; root translation in file units
  MotionSpec spec;              // what was made: speed and turn clamped, side chosen, unused fields zeroed
  std::vector<LegTrack> legs;   // one per leg limb, in Creature::limbs order
  GaitPattern gait;             // empty phases without a gait
  double gait_frequency = 0.0;  // stride cycles per second (0 without a gait), e.g. 1.1
};

// Throws std::invalid_argument when the spec is invalid or the plan does not
// support the action. Same creature and spec -> the same motion, bit for bit.
SynthesizedMotion synthesize_motion(const Creature& creature, const MotionSpec& spec);

// ---- Inverse kinematics, usable on their own -------------------------------

// Middle joint of a two-bone chain from `root` towards `target` (lengths
// upper, lower), bent towards `pole`. Out-of-reach targets straighten it.
Vec3 two_bone_middle(const Vec3& root, const Vec3& target, double upper, double lower, const Vec3& pole);
// FABRIK: moves the chain `positions` (root first) so its last point reaches
// `target` with segment i of length lengths[i], keeping the root; the initial
// shape (whose segment lengths may differ) decides the bend. Out-of-reach
// targets stretch the chain towards them.
void fabrik(std::vector<Vec3>& positions, const std::vector<double>& lengths, const Vec3& target, int max_iterations = 64,
            double tolerance = 1e-9);
// Local rotations of chain[0 .. n-2] (written into `local_rotations`, (J) of
// one frame) that make every bone point from positions[k] to positions[k+1],
// each as the smallest rotation from its REST direction (the offset of
// chain[k+1]) as carried by its parent. `parent_global` is the global
// rotation of chain[0]'s parent. Returns the global rotation of chain[n-2].
// Bone lengths are the skeleton's: the positions only give directions.
Quat aim_chain(const Skeleton& skeleton, const std::vector<int>& chain, const std::vector<Vec3>& positions,
               const Quat& parent_global, Quat* local_rotations);

// ---- Deterministic random numbers (same on every platform) -----------------

// SplitMix64 mixing of two values: derived seeds, e.g. mix_seed(zoo_seed, creature_index).
uint64_t mix_seed(uint64_t a, uint64_t b);


}  // namespace nec::zoo
