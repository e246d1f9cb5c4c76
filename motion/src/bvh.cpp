// BVH reader and writer.
#include "nec/motion/bvh.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <charconv>
#include <cstdint>
#include <cmath>
#include <cstring>

namespace nec {
namespace {


bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// A printable excerpt of untrusted text for error messages.
std::string excerpt(std::string_view text) {
  constexpr size_t kMax = 32;
  std::string out;
  for (char c : text.substr(0, kMax)) {
    const auto u = static_cast<unsigned char>(c);
    out += (u >= 0x20 && u < 0x7f) ? c : '?';
  }
  if (text.size() > kMax) out += "...";
  return out;
}

// The value of eight decimal digits in the bytes of `chunk`, the first in its lowest byte (as little-endian
// memory holds text): neighbouring digits are joined into pairs, pairs into fours, fours into the eight, each
// step with one multiply across the whole word (no lane overflows into the next).
uint64_t eight_digits(uint64_t chunk) {
  const uint64_t digits = chunk & 0x0F0F0F0F0F0F0F0FULL;
  const uint64_t pairs = (digits & 0x00FF00FF00FF00FFULL) * 10 + ((digits >> 8) & 0x00FF00FF00FF00FFULL);
  const uint64_t fours = (pairs & 0x0000FFFF0000FFFFULL) * 100 + ((pairs >> 16) & 0x0000FFFF0000FFFFULL);
  return (fours & 0xFFFFFFFFULL) * 10000 + (fours >> 32);
}

// Reads the decimal digits at `p` into `value` (value * 10^n + their value) and adds their count to `digits`;
// returns the position after them. Eight bytes at a time where the text has them (little-endian machines),
// while the count stays within 19 digits; past that the value wraps and the caller rejects the number.
const char* read_digits(const char* p, const char* last, uint64_t& value, int& digits) {
  static constexpr uint64_t kPowers[] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000, 100000000};
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  while (last - p >= 8 && digits <= 11) {
    uint64_t chunk = 0;
    std::memcpy(&chunk, p, 8);
    // A byte is a digit when its high nibble is 3 and adding 6 keeps it so; a carry from a non-digit byte
    // reaches only bytes after it.
    const uint64_t not_digit = ((chunk & 0xF0F0F0F0F0F0F0F0ULL) ^ 0x3030303030303030ULL) |
                               (((chunk + 0x0606060606060606ULL) & 0xF0F0F0F0F0F0F0F0ULL) ^ 0x3030303030303030ULL);
    const int count = not_digit == 0 ? 8 : __builtin_ctzll(not_digit) / 8;
    if (count == 0) return p;
    value = value * kPowers[count] + eight_digits(chunk << (8 * (8 - count)));  // leading zero digits below
    digits += count;
    p += count;
    if (count < 8) return p;
  }
#endif
  for (; p != last && static_cast<unsigned>(*p - '0') < 10; ++p, ++digits) value = value * 10 + (*p - '0');
  return p;
}

// A plain decimal ("-12.3456", at most 19 digits, no exponent) whose digits as an integer w are at most 2^53
// and that has at most 22 digits after the point is w / 10^k with both operands exact doubles, so one IEEE
// division gives the correctly rounded value: the same double std::from_chars returns (Clinger's fast path).
// Reads one at `first` and returns the position after it, or nullptr when the text there is none of those.
// The caller checks that the number ends where its token does ("1.5e3" stops at the 'e'). Motion lines are
// almost all such numbers; anything else goes to std::from_chars.
const char* scan_plain_decimal(const char* first, const char* last, double& value) {
  static constexpr double kPowersOfTen[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                            1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const bool negative = first != last && *first == '-';
  const char* p = first + (negative ? 1 : 0);
  uint64_t digits_value = 0;
  int digits = 0;
  p = read_digits(p, last, digits_value, digits);
  int fraction = 0;
  if (p != last && *p == '.') {
    const int integer_digits = digits;
    p = read_digits(p + 1, last, digits_value, digits);
    fraction = digits - integer_digits;
  }
  if (digits == 0 || digits > 19 || digits_value > (uint64_t{1} << 53) || fraction > 22) return nullptr;
  const double magnitude = static_cast<double>(digits_value) / kPowersOfTen[fraction];
  value = negative ? -magnitude : magnitude;
  return p;
}

// Parses one finite number that must fill `token` exactly; false otherwise.
bool parse_double(std::string_view token, double& value) {
  const char* first = token.data();
  const char* last = first + token.size();
  if (first != last && *first == '+') ++first;
  if (first == last) return false;
  if (scan_plain_decimal(first, last, value) == last) return true;
  const auto [ptr, ec] = std::from_chars(first, last, value);
  return ec == std::errc() && ptr == last && std::isfinite(value);
}

// Hierarchy tokenizer: whitespace-separated tokens with their line numbers.
class Lexer {
 public:
  Lexer(std::string_view text, const std::string& name) : text_(text), name_(name) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;  // UTF-8 byte order mark
  }

  // Next token, or empty at the end of the text.
  std::string_view next() {
    skip_space();
    const size_t begin = pos_;
    while (pos_ < text_.size() && !is_blank(text_[pos_]) && text_[pos_] != '\n') ++pos_;
    token_line_ = line_;
    return text_.substr(begin, pos_ - begin);
  }

  // The rest of the current line, trimmed (a joint name may contain spaces).
  std::string_view rest_of_line() {
    while (pos_ < text_.size() && is_blank(text_[pos_])) ++pos_;
    const size_t begin = pos_;
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    size_t end = pos_;
    while (end > begin && is_blank(text_[end - 1])) --end;
    token_line_ = line_;
    return text_.substr(begin, end - begin);
  }

  std::string_view expect(std::string_view what) {
    const std::string_view token = next();
    if (token != what) fail("expected '" + std::string(what) + "', found " + describe(token));
    return token;
  }

  double number(const char* what) {
    const std::string_view token = next();
    double value = 0.0;
    if (!parse_double(token, value)) fail(std::string("bad ") + what + ": " + describe(token));
    return value;
  }

  [[noreturn]] void fail(const std::string& problem) const { throw InputError(name_, token_line_, problem); }

  static std::string describe(std::string_view token) {
    return token.empty() ? std::string("end of file") : "'" + excerpt(token) + "'";
  }

  size_t position() const { return pos_; }
  long line() const { return line_; }
  std::string_view text() const { return text_; }
  const std::string& name() const { return name_; }

 private:
  void skip_space() {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        ++line_;
      } else if (!is_blank(c)) {
        return;
      }
      ++pos_;
    }
  }

  std::string_view text_;
  const std::string& name_;
  size_t pos_ = 0;
  long line_ = 1;
  long token_line_ = 1;
};

std::optional<Channel> parse_channel(std::string_view token) {
  static constexpr std::string_view kNames[] = {"Xposition", "Yposition", "Zposition",
                                                "Xrotation", "Yrotation", "Zrotation"};
  for (int i = 0; i < 6; ++i) {
    if (token.size() == kNames[i].size() &&
        std::equal(token.begin(), token.end(), kNames[i].begin(),
                   [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) ==
                                               std::tolower(static_cast<unsigned char>(b)); })) {
      return static_cast<Channel>(i);
    }
  }
  return std::nullopt;
}

class HierarchyParser {
 public:
  HierarchyParser(Lexer& lexer, const BvhLimits& limits) : lex_(lexer), limits_(limits) {}

  Skeleton parse() {
    std::string_view token = lex_.next();
    if (token != "HIERARCHY") lex_.fail("expected 'HIERARCHY' at the start of the file, found " + Lexer::describe(token));
    token = lex_.next();
    if (token != "ROOT") lex_.fail("expected 'ROOT', found " + Lexer::describe(token));
    parse_joint(-1, 0);
    return std::move(skeleton_);
  }

 private:
  void parse_joint(int parent, int depth) {
    // Each level is a stack frame here and in the writer: a deep chain from a
    // small file must not overflow the stack (ASan or a 1 MB thread stack did at 4096).
    if (depth > limits_.max_depth) lex_.fail("joints nested more than " + std::to_string(limits_.max_depth) + " deep");
    std::string_view name = lex_.rest_of_line();
    bool brace_on_name_line = false;
    if (!name.empty() && name.back() == '{') {
      name.remove_suffix(1);
      while (!name.empty() && is_blank(name.back())) name.remove_suffix(1);
      brace_on_name_line = true;
    }
    if (name.empty()) lex_.fail("joint without a name");
    // "A{ {" cannot be told apart from "A {" once written back.
    if (name.back() == '{') lex_.fail("joint name '" + excerpt(name) + "' ends with '{'");
    if (skeleton_.joint_count() >= limits_.max_joints) {
      lex_.fail("more than " + std::to_string(limits_.max_joints) + " joints");
    }
    if (skeleton_.find(name) >= 0) lex_.fail("duplicate joint name '" + excerpt(name) + "'");
    const int joint = skeleton_.add_joint(std::string(name), parent, Vec3::Zero(), ChannelLayout{});
    if (!brace_on_name_line) lex_.expect("{");
    bool has_offset = false;
    while (true) {
      const std::string_view token = lex_.next();
      if (token == "OFFSET") {
        Vec3 offset;
        for (int k = 0; k < 3; ++k) offset[k] = lex_.number("OFFSET value");
        skeleton_.offsets[joint] = offset;
        has_offset = true;
      } else if (token == "CHANNELS") {
        parse_channels(joint);
      } else if (token == "JOINT") {
        parse_joint(joint, depth + 1);
      } else if (token == "End") {
        lex_.expect("Site");
        parse_end_site(joint);
      } else if (token == "}") {
        break;
      } else {
        lex_.fail("unexpected " + Lexer::describe(token) + " in joint '" + excerpt(name) + "'");
      }
    }
    if (!has_offset) lex_.fail("joint '" + excerpt(name) + "' has no OFFSET");
  }

  void parse_channels(int joint) {
    const std::string_view count_token = lex_.next();
    int count = -1;
    const auto [ptr, ec] = std::from_chars(count_token.data(), count_token.data() + count_token.size(), count);
    if (ec != std::errc() || ptr != count_token.data() + count_token.size() || count < 0 || count > 6) {
      lex_.fail("bad channel count " + Lexer::describe(count_token) + " (must be 0 to 6)");
    }
    ChannelLayout layout;
    for (int i = 0; i < count; ++i) {
      const std::string_view token = lex_.next();
      const auto channel = parse_channel(token);
      if (!channel) lex_.fail("unknown channel " + Lexer::describe(token));
      if (layout.has(*channel)) lex_.fail("channel " + Lexer::describe(token) + " listed twice");
      layout.push(*channel);
    }
    skeleton_.channels[joint] = layout;
  }

  void parse_end_site(int joint) {
    lex_.expect("{");
    EndSite site{joint, Vec3::Zero()};
    while (true) {
      const std::string_view token = lex_.next();
      if (token == "OFFSET") {
        for (int k = 0; k < 3; ++k) site.offset[k] = lex_.number("OFFSET value");
      } else if (token == "}") {
        break;
      } else {
        lex_.fail("unexpected " + Lexer::describe(token) + " in End Site");
      }
    }
    skeleton_.end_sites.push_back(site);
  }

  Lexer& lex_;
  const BvhLimits& limits_;
  Skeleton skeleton_;
};

// The Taylor coefficients after the first one or two terms, highest power first: sine's from x^17 down to x^3
// (divided by x), cosine's from x^16 down to x^2.
constexpr double kSineTerms[] = {1.0 / 355687428096000.0, -1.0 / 1307674368000.0, 1.0 / 6227020800.0,
                                 -1.0 / 39916800.0,       1.0 / 362880.0,          -1.0 / 5040.0,
                                 1.0 / 120.0,             -1.0 / 6.0};
constexpr double kCosineTerms[] = {1.0 / 20922789888000.0, -1.0 / 87178291200.0, 1.0 / 479001600.0,
                                   -1.0 / 3628800.0,       1.0 / 40320.0,        -1.0 / 720.0,
                                   1.0 / 24.0,             -0.5};

// Horner's rule in x^2 over `terms`.
template <size_t N>
double taylor_series(const double (&terms)[N], double r2) {
  double sum = terms[0];
  for (size_t i = 1; i < N; ++i) sum = sum * r2 + terms[i];
  return sum;
}

// sin and cos of half of `degrees`, within 2 ulp of the exact values: reduced exactly in degrees to at most 45
// from the nearest multiple of 90 (so no digits of pi are lost), then Taylor polynomials to the 17th and 16th
// power, whose next terms are below half an ulp on [-pi/4, pi/4]. Inline, it costs a third of libm's sincos,
// which took a fifth of parsing a BVH file.
void half_angle_sin_cos(double degrees, double& sine, double& cosine) {
  const double half = 0.5 * degrees;
  if (!(std::fabs(half) < 1e15)) {  // not finite, or too far out for the reduction below to be exact
    sine = std::sin(half / kDegreesPerRadian);
    cosine = std::cos(half / kDegreesPerRadian);
    return;
  }
  const double quarter_turns = std::nearbyint(half / 90.0);
  const double r = (half - 90.0 * quarter_turns) * (3.14159265358979323846 / 180.0);
  const double r2 = r * r;
  const double s = r + r * r2 * taylor_series(kSineTerms, r2);
  const double c = 1.0 + r2 * taylor_series(kCosineTerms, r2);
  switch (static_cast<int64_t>(quarter_turns) & 3) {
    case 0: sine = s; cosine = c; break;
    case 1: sine = c; cosine = -s; break;
    case 2: sine = -s; cosine = -c; break;
    default: sine = -c; cosine = s; break;
  }
}

// rotation * axis_rotation(axis, degrees) without the general product's terms that are zero.
void turn_about_axis(Quat& rotation, int axis, double degrees) {
  double s, c;
  half_angle_sin_cos(degrees, s, c);
  double* q = rotation.coeffs().data();  // x, y, z, w
  const int next = (axis + 1) % 3, last = (axis + 2) % 3;
  const double w = q[3], along = q[axis], b = q[next], d = q[last];
  q[3] = w * c - along * s;
  q[axis] = along * c + w * s;
  q[next] = b * c + d * s;
  q[last] = d * c - b * s;
}

// Applies one frame of channel values to the motion.
void decode_frame(const Skeleton& skeleton, const double* values, int frame, Motion& motion) {
  for (int j = 0; j < skeleton.joint_count(); ++j) {
    const ChannelLayout& layout = skeleton.channels[j];
    Vec3 translation = skeleton.offsets[j];
    Quat rotation = Quat::Identity();
    for (int c = 0; c < layout.count; ++c) {
      const Channel channel = layout.channels[c];
      const double value = *values++;
      if (is_position(channel)) {
        translation[channel_axis(channel)] = value;
      } else {
        turn_about_axis(rotation, channel_axis(channel), value);
      }
    }
    motion.rotation(frame, j) = rotation.normalized();
    motion.translation(frame, j) = translation;
  }
}

class MotionParser {
 public:
  MotionParser(Lexer& lexer, const BvhLimits& limits) : lex_(lexer), limits_(limits) {}

  Motion parse(const Skeleton& skeleton) {
    const std::string_view keyword = lex_.next();
    if (keyword != "MOTION") lex_.fail("expected 'MOTION' after the hierarchy, found " + Lexer::describe(keyword));
    const long frames = parse_frame_count();
    const double frame_time = parse_frame_time();

    int channel_count = 0;
    for (const ChannelLayout& layout : skeleton.channels) channel_count += layout.count;
    if (channel_count == 0 && frames > 0) lex_.fail("the hierarchy has no channels, so no frame can be read");

    // Every number takes at least one character and one separator: reject
    // counts the rest of the file cannot hold before allocating anything.
    const std::string_view text = lex_.text();
    const size_t remaining = text.size() - lex_.position();
    const double needed = static_cast<double>(frames) * channel_count * 2.0 - 1.0;
    if (frames > 0 && needed > static_cast<double>(remaining)) {
      throw InputError(lex_.name(), frames_line_,
                       "declares " + std::to_string(frames) + " frames of " + std::to_string(channel_count) +
                           " channels, but only " + std::to_string(remaining) + " bytes of motion data follow");
    }
    // Joints without channels take no text but a quaternion and a translation
    // per frame: bound the memory by the text too (real files have well under
    // one joint-frame per byte; a 64 KB file asked for 1 GB).
    const double joint_frames = static_cast<double>(frames) * skeleton.joint_count();
    if (joint_frames > limits_.max_joint_frames_per_byte * static_cast<double>(remaining) + skeleton.joint_count()) {
      throw InputError(lex_.name(), frames_line_,
                       "declares " + std::to_string(frames) + " frames of " + std::to_string(skeleton.joint_count()) +
                           " joints, more joint-frames than " + std::to_string(remaining) +
                           " bytes of motion data can describe (at most " +
                           std::to_string(static_cast<int>(limits_.max_joint_frames_per_byte)) + " per byte)");
    }

    Motion motion;
    motion.fps = 1.0 / frame_time;
    motion.frame_count = static_cast<int>(frames);
    motion.joint_count = skeleton.joint_count();
    motion.rotations.resize(static_cast<size_t>(frames) * motion.joint_count);
    motion.translations.resize(motion.rotations.size());

    std::vector<double> values(channel_count);
    const char* p = text.data() + lex_.position();
    const char* end = text.data() + text.size();
    long line = lex_.line();
    // Move past the end of the "Frame Time" line.
    while (p < end && *p != '\n') {
      if (!is_blank(*p)) throw InputError(lex_.name(), line, "unexpected text after the frame time");
      ++p;
    }
    for (long frame = 0; frame < frames;) {
      if (p >= end) {
        throw InputError(lex_.name(), line, "file ends after " + std::to_string(frame) + " of " +
                                                std::to_string(frames) + " declared frames");
      }
      ++p;  // the '\n' that ended the previous line
      ++line;
      int count = 0;
      while (true) {
        while (p < end && is_blank(*p)) ++p;
        if (p >= end || *p == '\n') break;
        if (count == channel_count) {
          throw InputError(lex_.name(), line, "frame " + std::to_string(frame) + " has more than " +
                                                  std::to_string(channel_count) + " values");
        }
        // A plain decimal is read in the pass that finds its end; any other token is cut out and parsed whole.
        const char* after = scan_plain_decimal(p, end, values[count]);
        if (after != nullptr && (after == end || is_blank(*after) || *after == '\n')) {
          p = after;
        } else {
          const char* start = p;
          while (p < end && !is_blank(*p) && *p != '\n') ++p;
          const std::string_view token(start, static_cast<size_t>(p - start));
          if (!parse_double(token, values[count])) {
            throw InputError(lex_.name(), line, "bad number '" + excerpt(token) + "' in frame " + std::to_string(frame));
          }
        }
        ++count;
      }
      if (count == 0) continue;  // blank line
      if (count != channel_count) {
        throw InputError(lex_.name(), line, "frame " + std::to_string(frame) + " has " + std::to_string(count) +
                                                " values, expected " + std::to_string(channel_count));
      }
      decode_frame(skeleton, values.data(), static_cast<int>(frame), motion);
      ++frame;
    }
    // Lines after the declared frames are ignored, as other readers do, with a warning.
    long extra_lines = 0;
    bool line_has_text = false;
    for (; p < end; ++p) {
      if (*p == '\n') {
        extra_lines += line_has_text;
        line_has_text = false;
      } else if (!is_blank(*p)) {
        line_has_text = true;
      }
    }
    extra_lines += line_has_text;
    if (extra_lines > 0) {
      warnings_.push_back("ignored " + std::to_string(extra_lines) + " line(s) after the " + std::to_string(frames) +
                          " declared frames");
    }
    return motion;
  }

 private:
  long parse_frame_count() {
    std::string_view token = lex_.next();
    frames_line_ = lex_.line();
    std::string_view number;
    if (token == "Frames:") {
      number = lex_.next();
    } else if (token.substr(0, 7) == "Frames:") {
      number = token.substr(7);
    } else {
      lex_.fail("expected 'Frames:', found " + Lexer::describe(token));
    }
    long frames = -1;
    const auto [ptr, ec] = std::from_chars(number.data(), number.data() + number.size(), frames);
    if (ec != std::errc() || ptr != number.data() + number.size() || frames < 0 || frames > 2147483647L) {
      lex_.fail("bad frame count " + Lexer::describe(number) + " (must be a whole number >= 0)");
    }
    return frames;
  }

  double parse_frame_time() {
    std::string_view token = lex_.next();
    std::string_view number;
    if (token == "Frame") {
      token = lex_.next();
      if (token == "Time:") {
        number = lex_.next();
      } else if (token.substr(0, 5) == "Time:") {
        number = token.substr(5);
      } else {
        lex_.fail("expected 'Frame Time:', found " + Lexer::describe(token));
      }
    } else {
      lex_.fail("expected 'Frame Time:', found " + Lexer::describe(token));
    }
    double frame_time = 0.0;
    if (!parse_double(number, frame_time) || frame_time < limits_.min_frame_time ||
        frame_time > limits_.max_frame_time) {
      lex_.fail("bad frame time " + Lexer::describe(number) + " (seconds per frame, must be in [" +
                std::to_string(limits_.min_frame_time) + ", " + std::to_string(limits_.max_frame_time) + "])");
    }
    return frame_time;
  }

  Lexer& lex_;
  const BvhLimits& limits_;
  long frames_line_ = 0;

 public:
  std::vector<std::string> warnings_;
};

// ---- writer ----

void append_number(std::string& out, double value) {
  if (value == 0.0) value = 0.0;  // no "-0"
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::general, 8);
  out.append(buffer, result.ptr);
}

void append_vec(std::string& out, const Vec3& v) {
  for (int k = 0; k < 3; ++k) {
    out += ' ';
    append_number(out, v[k]);
  }
}

// Angle in (-180, 180].
double wrap_degrees(double degrees) {
  const double wrapped = std::remainder(degrees, 360.0);
  return wrapped == -180.0 ? 180.0 : wrapped;
}

// Euler angles of `rotation` for the rotation channels of `layout`. A layout
// with fewer than 3 rotation channels drops the trailing angles, so of the two
// equivalent triples (a, b, c) and (a + 180, 180 - b, c + 180) it takes the one
// whose dropped angles are nearer 0: a Z-then-Y joint at Y = 135 is
// (Z + 180, 45, X = 180) in the first and (Z, 135, 0) in the second.
Vec3 channel_euler(const Quat& rotation, const ChannelLayout& layout) {
  const Vec3 euler = quat_to_euler(rotation, layout.euler_order());
  const int kept = layout.rotation_count();
  if (kept == 3) return euler;
  const Vec3 other(wrap_degrees(euler[0] + 180.0), wrap_degrees(180.0 - euler[1]), wrap_degrees(euler[2] + 180.0));
  double dropped = 0.0;
  double other_dropped = 0.0;
  for (int k = kept; k < 3; ++k) {
    dropped += std::abs(euler[k]);
    other_dropped += std::abs(other[k]);
  }
  return other_dropped < dropped ? other : euler;
}

class Writer {
 public:
  Writer(const Skeleton& skeleton, const BvhWriteOptions& options)
      : skeleton_(skeleton), children_(skeleton.children_lists()), layouts_(skeleton.channels) {
    if (options.euler_order) {
      // Only full rotation layouts are reordered: a joint with two rotation
      // channels cannot hold its rotations in the other order of its two axes.
      for (ChannelLayout& layout : layouts_) {
        if (layout.rotation_count() == 3) layout = layout.with_euler_order(*options.euler_order);
      }
    }
  }

  std::string write(const Motion& motion) {
    std::string out;
    out.reserve(static_cast<size_t>(motion.frame_count) * skeleton_.joint_count() * 40 + 4096);
    out += "HIERARCHY\n";
    write_joint(out, 0, 0);
    out += "MOTION\nFrames: ";
    out += std::to_string(motion.frame_count);
    out += "\nFrame Time: ";
    append_number(out, 1.0 / motion.fps);
    out += '\n';
    for (int t = 0; t < motion.frame_count; ++t) {
      bool first = true;
      for (int j : order_) {
        const ChannelLayout& layout = layouts_[j];
        if (layout.count == 0) continue;
        const Vec3 euler = channel_euler(motion.rotation(t, j), layout);
        const Vec3& translation = motion.translation(t, j);
        int rotation_index = 0;
        for (int c = 0; c < layout.count; ++c) {
          if (!first) out += ' ';
          first = false;
          const Channel channel = layout.channels[c];
          append_number(out, is_position(channel) ? translation[channel_axis(channel)] : euler[rotation_index++]);
        }
      }
      out += '\n';
    }
    return out;
  }

 private:
  void write_joint(std::string& out, int joint, int depth) {
    order_.push_back(joint);
    const std::string indent(static_cast<size_t>(depth) * 2, ' ');
    out += indent;
    out += joint == 0 ? "ROOT " : "JOINT ";
    out += skeleton_.names[joint];
    out += '\n' + indent + "{\n" + indent + "  OFFSET";
    append_vec(out, skeleton_.offsets[joint]);
    out += '\n';
    const ChannelLayout& layout = layouts_[joint];
    out += indent + "  CHANNELS " + std::to_string(layout.count);
    for (int c = 0; c < layout.count; ++c) {
      out += ' ';
      out += channel_name(layout.channels[c]);
    }
    out += '\n';
    for (int child : children_[joint]) write_joint(out, child, depth + 1);
    for (const EndSite& site : skeleton_.end_sites) {
      if (site.parent != joint) continue;
      out += indent + "  End Site\n" + indent + "  {\n" + indent + "    OFFSET";
      append_vec(out, site.offset);
      out += '\n' + indent + "  }\n";
    }
    out += indent + "}\n";
  }

  const Skeleton& skeleton_;
  std::vector<std::vector<int>> children_;
  std::vector<ChannelLayout> layouts_;
  std::vector<int> order_;  // joints in the order they are written
};

}  // namespace

Clip parse_bvh(std::string_view text, const std::string& name, const BvhLimits& limits) {
  if (text.find_first_not_of(" \t\r\n") == std::string_view::npos) throw InputError(name, 0, "file is empty");
  Lexer lexer(text, name);
  Clip clip;
  clip.skeleton = HierarchyParser(lexer, limits).parse();
  MotionParser motion_parser(lexer, limits);
  clip.motion = motion_parser.parse(clip.skeleton);
  clip.warnings = std::move(motion_parser.warnings_);
  return clip;
}

Clip read_bvh(const std::string& path, const BvhLimits& limits) {
  const std::string text = read_file(path);
  return parse_bvh(text, path, limits);
}

std::string format_bvh(const Skeleton& skeleton, const Motion& motion, const BvhWriteOptions& options) {
  skeleton.validate();
  if (motion.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument("format_bvh: motion has " + std::to_string(motion.joint_count) +
                                " joints, skeleton has " + std::to_string(skeleton.joint_count()));
  }
  return Writer(skeleton, options).write(motion);
}

void write_bvh(const std::string& path, const Skeleton& skeleton, const Motion& motion,
               const BvhWriteOptions& options) {
  write_file_atomic(path, format_bvh(skeleton, motion, options));
}

}  // namespace nec
