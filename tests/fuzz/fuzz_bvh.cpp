// libFuzzer target for the BVH reader and writer.
//
// Contract checked on every input:
//   - parse_bvh either returns a clip or throws nec::InputError; any other
//     exception, crash, leak or undefined behaviour is a finding.
//   - A clip that was read is written back (its own Euler orders, then one
//     order picked from the input) and must read again without any error, with
//     the same joints, parents, channel layouts, end sites and frame count, and
//     the same motion up to the writer's 8 significant digits.
// Run through scripts/fuzz.sh.
#include "nec/motion/bvh.h"
#include "nec/motion/error.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

namespace {

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_bvh: %s: %s\n", what, detail.c_str());
  std::abort();
}

// Largest tolerated rotation difference (radians) after a write/read cycle;
// 8 significant digits of degrees give about 1e-7 rad, gimbal-lock
// neighbourhoods lose a little more.
constexpr double kRotationTolerance = 1e-4;
// Translations are written with 8 significant digits.
constexpr double kRelativeTranslationTolerance = 1e-6;

void expect_same_clip(const nec::Clip& original, const nec::Clip& back, const char* pass) {
  const nec::Skeleton& a = original.skeleton;
  const nec::Skeleton& b = back.skeleton;
  if (a.names != b.names) fail(pass, "joint names differ after the round trip");
  if (a.parents != b.parents) fail(pass, "parents differ after the round trip");
  if (a.end_sites.size() != b.end_sites.size()) fail(pass, "end site count differs after the round trip");
  for (int j = 0; j < a.joint_count(); ++j) {
    if (a.channels[j].count != b.channels[j].count) fail(pass, "channel count differs at joint " + a.names[j]);
    if (a.channels[j].has_position() != b.channels[j].has_position()) {
      fail(pass, "position channels differ at joint " + a.names[j]);
    }
  }
  const nec::Motion& ma = original.motion;
  const nec::Motion& mb = back.motion;
  if (ma.frame_count != mb.frame_count) fail(pass, "frame count differs after the round trip");
  if (std::abs(ma.fps - mb.fps) > 1e-6 * ma.fps) {
    fail(pass, "fps " + std::to_string(ma.fps) + " became " + std::to_string(mb.fps));
  }
  for (size_t i = 0; i < ma.rotations.size(); ++i) {
    const double angle = ma.rotations[i].angularDistance(mb.rotations[i]);
    if (!(angle <= kRotationTolerance)) {
      fail(pass, "rotation of joint-frame " + std::to_string(i) + " moved by " + std::to_string(angle) + " rad");
    }
    const double scale = std::max(1.0, ma.translations[i].cwiseAbs().maxCoeff());
    const double moved = (ma.translations[i] - mb.translations[i]).cwiseAbs().maxCoeff();
    if (!(moved <= kRelativeTranslationTolerance * scale)) {
      fail(pass, "translation of joint-frame " + std::to_string(i) + " moved by " + std::to_string(moved));
    }
  }
}

void round_trip(const nec::Clip& clip, const nec::BvhWriteOptions& options, const char* pass) {
  const std::string written = nec::format_bvh(clip.skeleton, clip.motion, options);
  nec::Clip back;
  try {
    back = nec::parse_bvh(written, "rewritten.bvh");
  } catch (const nec::InputError& e) {
    fail(pass, std::string("our own output does not read back: ") + e.what());
  }
  expect_same_clip(clip, back, pass);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    nec::Clip clip;
    try {
      clip = nec::parse_bvh(text, "fuzz.bvh");
    } catch (const nec::InputError&) {
      return 0;  // rejected with a message: the expected outcome for bad input
    }
    round_trip(clip, {}, "round trip");
    nec::BvhWriteOptions reordered;
    reordered.euler_order = static_cast<nec::EulerOrder>(size % 6);
    round_trip(clip, reordered, "round trip with another Euler order");
  } catch (const std::exception& e) {
    fail("unexpected exception", e.what());
  }
  return 0;
}
