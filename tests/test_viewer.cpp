// nec_viewer: checksums, the zlib stream and PNG file (decoded by an
// independent inflate and unfilter written here from RFC 1950/1951 and the PNG
// spec), anti-aliased drawing, strips (bones drawn where forward kinematics
// puts them, the whole motion inside every panel, the side view) and the HTML
// page (clips, captions, three.js, nothing that reaches the network).
#include "nec/motion/bvh.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "nec/viewer/html.h"
#include "nec/viewer/png.h"
#include "nec/viewer/raster.h"
#include "nec/viewer/strip.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

namespace nec::viewer {
namespace {

namespace fs = std::filesystem;

// ---- A minimal inflate (stored and fixed-Huffman blocks) and PNG decoder ----

class BitReader {
 public:
  explicit BitReader(std::string_view data) : data_(data) {}
  int bit() {
    if (position_ >= data_.size() * 8) throw std::runtime_error("inflate: out of data");
    const int b = (static_cast<unsigned char>(data_[position_ / 8]) >> (position_ % 8)) & 1;
    ++position_;
    return b;
  }
  int bits(int count) {  // least significant bit first
    int value = 0;
    for (int i = 0; i < count; ++i) value |= bit() << i;
    return value;
  }
  int code(int count) {  // Huffman code, most significant bit first
    int value = 0;
    for (int i = 0; i < count; ++i) value = (value << 1) | bit();
    return value;
  }
  void align() { position_ = (position_ + 7) / 8 * 8; }
  size_t byte_position() const { return position_ / 8; }
  void skip_bytes(size_t n) { position_ += 8 * n; }

 private:
  std::string_view data_;
  size_t position_ = 0;
};

int fixed_symbol(BitReader& in) {
  int c = in.code(7);
  if (c <= 23) return 256 + c;
  c = (c << 1) | in.bit();
  if (c >= 0x30 && c <= 0xBF) return c - 0x30;
  if (c >= 0xC0 && c <= 0xC7) return 280 + c - 0xC0;
  c = (c << 1) | in.bit();
  if (c >= 0x190 && c <= 0x1FF) return 144 + c - 0x190;
  throw std::runtime_error("inflate: bad fixed code");
}

std::string inflate_zlib(std::string_view stream) {
  static const int kLengthBase[] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                    31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
  static const int kLengthExtra[] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
  static const int kDistanceBase[] = {1,    2,    3,    4,    5,    7,     9,     13,    17,  25,
                                      33,   49,   65,   97,   129,  193,   257,   385,   513, 769,
                                      1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
  static const int kDistanceExtra[] = {0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};
  if (stream.size() < 6) throw std::runtime_error("zlib: too short");
  const int cmf = static_cast<unsigned char>(stream[0]), flg = static_cast<unsigned char>(stream[1]);
  if ((cmf & 15) != 8 || (cmf * 256 + flg) % 31 != 0 || (flg & 32)) throw std::runtime_error("zlib: bad header");
  BitReader in(stream.substr(2));
  std::string out;
  for (bool final = false; !final;) {
    final = in.bit();
    const int type = in.bits(2);
    if (type == 0) {
      in.align();
      const size_t at = in.byte_position() + 2;
      const int length = in.bits(16);
      const int complement = in.bits(16);
      if ((length ^ 0xFFFF) != complement) throw std::runtime_error("inflate: bad stored length");
      out.append(stream.substr(at + 4, length));
      in.skip_bytes(length);
    } else if (type == 1) {
      for (;;) {
        const int symbol = fixed_symbol(in);
        if (symbol < 256) {
          out.push_back(static_cast<char>(symbol));
        } else if (symbol == 256) {
          break;
        } else {
          const int l = symbol - 257;
          if (l >= 29) throw std::runtime_error("inflate: bad length symbol");
          const int length = kLengthBase[l] + in.bits(kLengthExtra[l]);
          const int d = in.code(5);
          if (d >= 30) throw std::runtime_error("inflate: bad distance symbol");
          const size_t distance = kDistanceBase[d] + in.bits(kDistanceExtra[d]);
          if (distance > out.size()) throw std::runtime_error("inflate: distance before the start");
          for (int i = 0; i < length; ++i) out.push_back(out[out.size() - distance]);
        }
      }
    } else {
      throw std::runtime_error("inflate: block type " + std::to_string(type) + " not expected");
    }
  }
  in.align();
  const size_t end = in.byte_position() + 2;
  if (end + 4 != stream.size()) throw std::runtime_error("zlib: trailing bytes");
  std::uint32_t adler = 0;
  for (int i = 0; i < 4; ++i) adler = (adler << 8) | static_cast<unsigned char>(stream[end + i]);
  if (adler != adler32(out)) throw std::runtime_error("zlib: Adler-32 mismatch");
  return out;
}

std::uint32_t read_u32(std::string_view bytes, size_t at) {
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i) value = (value << 8) | static_cast<unsigned char>(bytes[at + i]);
  return value;
}

// Decodes an 8-bit RGB PNG, checking the signature, chunk CRCs and order.
Image decode_png(std::string_view png) {
  if (png.substr(0, 8) != std::string_view("\x89PNG\r\n\x1a\n", 8)) throw std::runtime_error("png: bad signature");
  size_t at = 8;
  Image image;
  std::string idat;
  std::vector<std::string> types;
  while (at < png.size()) {
    const std::uint32_t length = read_u32(png, at);
    const std::string type(png.substr(at + 4, 4));
    const std::string_view body = png.substr(at + 8, length);
    if (read_u32(png, at + 8 + length) != crc32(png.substr(at + 4, 4 + length))) throw std::runtime_error("png: CRC of " + type);
    types.push_back(type);
    if (type == "IHDR") {
      image.width = static_cast<int>(read_u32(body, 0));
      image.height = static_cast<int>(read_u32(body, 4));
      if (body.substr(8, 5) != std::string_view("\x08\x02\x00\x00\x00", 5)) throw std::runtime_error("png: not 8-bit RGB");
    } else if (type == "IDAT") {
      idat.append(body);
    }
    at += 12 + length;
  }
  if (types.front() != "IHDR" || types.back() != "IEND") throw std::runtime_error("png: chunk order");
  const std::string raw = inflate_zlib(idat);
  const size_t stride = static_cast<size_t>(image.width) * 3;
  if (raw.size() != (stride + 1) * image.height) throw std::runtime_error("png: wrong amount of pixel data");
  std::vector<unsigned char> previous(stride, 0), current(stride);
  image.pixels.resize(static_cast<size_t>(image.width) * image.height);
  for (int y = 0; y < image.height; ++y) {
    const int filter = static_cast<unsigned char>(raw[y * (stride + 1)]);
    for (size_t i = 0; i < stride; ++i) {
      const int x = static_cast<unsigned char>(raw[y * (stride + 1) + 1 + i]);
      const int a = i >= 3 ? current[i - 3] : 0, b = previous[i], c = i >= 3 ? previous[i - 3] : 0;
      const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
      const int paeth = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      const int predictor = filter == 0 ? 0 : filter == 1 ? a : filter == 2 ? b : filter == 3 ? (a + b) / 2 : paeth;
      if (filter > 4) throw std::runtime_error("png: bad filter");
      current[i] = static_cast<unsigned char>(x + predictor);
    }
    for (int x = 0; x < image.width; ++x) image.at(x, y) = {current[x * 3], current[x * 3 + 1], current[x * 3 + 2]};
    std::swap(previous, current);
  }
  return image;
}

// ---- Checksums, zlib, PNG ----

TEST(Png, ChecksumsMatchPublishedValues) {
  EXPECT_EQ(crc32("123456789"), 0xCBF43926u);
  EXPECT_EQ(crc32("IEND"), 0xAE426082u);  // the constant CRC that ends every PNG file
  EXPECT_EQ(crc32("5678", crc32("1234")), crc32("12345678"));
  EXPECT_EQ(adler32("Wikipedia"), 0x11E60398u);
  EXPECT_EQ(adler32(""), 1u);
  const std::string long_run(100000, '\xff');  // exercises the modulo between runs
  EXPECT_EQ(adler32(long_run.substr(50000), adler32(long_run.substr(0, 50000))), adler32(long_run));
}

TEST(Png, ZlibStreamsInflateToTheirInput) {
  std::mt19937 rng(7);
  std::string random_bytes(70000, '\0');  // more than one stored block
  for (char& c : random_bytes) c = static_cast<char>(rng() & 0xFF);
  std::string text;
  for (int i = 0; i < 2000; ++i) text += "frame " + std::to_string(i % 37) + " hips 0.5 1.25 -3\n";
  for (const std::string& input : {std::string(), std::string("a"), random_bytes, text, std::string(100000, 'z')}) {
    for (Deflate method : {Deflate::Stored, Deflate::FixedHuffman}) {
      const std::string stream = zlib_compress(input, method);
      EXPECT_EQ(inflate_zlib(stream), input) << "size " << input.size();
    }
  }
  const size_t compressed = zlib_compress(text).size();
  EXPECT_LT(compressed, text.size() / 8) << "LZ77 should find the repeated lines: " << compressed << " of " << text.size();
}

TEST(Png, DecodesToTheSamePixels) {
  Image image(37, 23);
  std::mt19937 rng(3);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      // Smooth areas (Sub/Up/Paeth win), noise (None wins) and flat rows.
      const bool noisy = y % 7 == 3;
      image.at(x, y) = noisy ? Rgb{static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng())}
                             : Rgb{static_cast<std::uint8_t>(x * 7), static_cast<std::uint8_t>(y * 11), static_cast<std::uint8_t>((x + y) * 3)};
    }
  }
  for (Deflate method : {Deflate::Stored, Deflate::FixedHuffman}) {
    const Image decoded = decode_png(encode_png(image, method));
    ASSERT_EQ(decoded.width, image.width);
    ASSERT_EQ(decoded.height, image.height);
    EXPECT_TRUE(decoded.pixels == image.pixels);
  }
  EXPECT_THROW(encode_png(Image()), std::invalid_argument);
}

TEST(Png, WritesTheFileAtomically) {
  const fs::path path = fs::temp_directory_path() / ("nec_viewer_" + std::to_string(::getpid()) + ".png");
  Image image(4, 2, {10, 20, 30});
  write_png(path.string(), image);
  std::ifstream file(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(decode_png(bytes).pixels == image.pixels);
  fs::remove(path);
}

// ---- Drawing ----

TEST(Raster, SegmentsAreAntiAliasedAndWhereAsked) {
  Image image(40, 20);
  const Rgb ink{0, 0, 0};
  draw_segment(image, {5.0, 10.5}, {35.0, 10.5}, 2.0, ink);  // through the centres of row 10
  EXPECT_EQ(image.at(20, 9), ink);  // centres up to 1 px from the line: fully covered
  EXPECT_EQ(image.at(20, 10), ink);
  EXPECT_EQ(image.at(20, 11), ink);
  EXPECT_EQ(image.at(20, 15), Rgb({255, 255, 255}));
  EXPECT_EQ(image.at(20, 5), Rgb({255, 255, 255}));
  // Centres 2 px away = on the edge of a radius-2 line: half covered.
  EXPECT_NEAR(image.at(20, 12).r, 128, 1);
  EXPECT_NEAR(image.at(20, 8).r, 128, 1);
  // Round cap: the end pixel is covered, beyond the cap is not.
  EXPECT_EQ(image.at(36, 10).r, 0);
  EXPECT_EQ(image.at(39, 10).r, 255);

  Image disc(21, 21);
  draw_disc(disc, {10.5, 10.5}, 5.0, ink);
  int partial = 0;
  for (const Rgb& p : disc.pixels) partial += p.r > 0 && p.r < 255;
  EXPECT_GT(partial, 8) << "edge pixels should be blended";
  EXPECT_EQ(disc.at(10, 10).r, 0);
  EXPECT_EQ(disc.at(10, 2).r, 255);
  EXPECT_EQ(disc.at(10, 16).r, 255);
}

TEST(Raster, TextDrawsKnownGlyphs) {
  Image image(text_width("frame 12  0.40 s", 1) + 2, 9);
  draw_text(image, 1, 1, "frame 12  0.40 s", 1, {0, 0, 0});
  int inked = 0;
  for (const Rgb& p : image.pixels) inked += p.r == 0;
  EXPECT_GT(inked, 60);
  EXPECT_EQ(text_width("ab", 2), 22);
  Image blank(20, 9);
  draw_text(blank, 1, 1, "XYZ", 1, {0, 0, 0});  // unknown characters stay blank
  for (const Rgb& p : blank.pixels) EXPECT_EQ(p.r, 255);
}

// ---- Strips ----

bool is_ink(const Rgb& p) { return p != Rgb{255, 255, 255} && p != Rgb{243, 243, 238}; }  // not background or ground

bool ink_near(const Image& image, const Point& at, int reach) {
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      const int x = static_cast<int>(std::floor(at.x())) + dx, y = static_cast<int>(std::floor(at.y())) + dy;
      if (image.contains(x, y) && is_ink(image.at(x, y))) return true;
    }
  }
  return false;
}

TEST(Strip, DrawsBonesWhereForwardKinematicsPutsThem) {
  const Clip clip = read_bvh(testing::cmu_bvh_dir() + "/01_01.bvh");
  StripOptions options;
  options.frames = 5;
  options.panel_height = 240;
  const StripView view = plan_strip(clip, options);
  const Image strip = draw_strip(clip, view);
  ASSERT_EQ(strip.width, view.width());
  ASSERT_EQ(strip.height, 240);
  EXPECT_EQ(view.frames.front(), 0);
  EXPECT_EQ(view.frames.back(), clip.motion.frame_count - 1);

  const Pose pose = forward_kinematics(clip.skeleton, clip.motion);
  int checked = 0;
  double lowest_row = 0.0;
  for (size_t panel = 0; panel < view.frames.size(); ++panel) {
    for (int j = 0; j < clip.skeleton.joint_count(); ++j) {
      const Point pixel = view.project(static_cast<int>(panel), pose.position(view.frames[panel], j));
      EXPECT_GE(pixel.x(), panel * view.panel_width);
      EXPECT_LT(pixel.x(), (panel + 1) * view.panel_width);
      EXPECT_TRUE(ink_near(strip, pixel, 1)) << "joint " << clip.skeleton.names[j] << " in panel " << panel << " at "
                                             << pixel.transpose();
      lowest_row = std::max(lowest_row, pixel.y());
      ++checked;
      // Halfway along every bone there is ink too.
      if (j > 0) {
        const Point parent = view.project(static_cast<int>(panel), pose.position(view.frames[panel], clip.skeleton.parents[j]));
        EXPECT_TRUE(ink_near(strip, 0.5 * (pixel + parent), 1)) << "bone to " << clip.skeleton.names[j];
      }
    }
  }
  EXPECT_EQ(checked, 5 * clip.skeleton.joint_count());
  EXPECT_LE(lowest_row, view.ground_row + 1.0);  // nothing below the ground line
  // Most of the strip is empty: a picture of bones, not a smear.
  int inked = 0;
  for (const Rgb& p : strip.pixels) inked += is_ink(p);
  EXPECT_GT(inked, 500);
  EXPECT_LT(inked, static_cast<int>(strip.pixels.size()) / 8);
}

TEST(Strip, EveryFrameFitsItsPanel) {
  std::mt19937 rng(11);
  Clip clip;
  clip.skeleton = testing::random_skeleton(rng, 9);
  clip.motion = testing::random_motion(rng, clip.skeleton, 30);
  StripOptions options;
  options.frames = 30;  // every frame shown
  options.panel_height = 100;
  options.up = UpAxis::Y;
  const StripView view = plan_strip(clip, options);
  const Pose pose = forward_kinematics(clip.skeleton, clip.motion);
  const std::vector<Vec3> sites = end_site_positions(clip.skeleton, pose);
  double lowest = 0.0;
  for (int t = 0; t < 30; ++t) {
    ASSERT_EQ(view.frames[t], t);
    std::vector<Vec3> points;
    for (int j = 0; j < clip.skeleton.joint_count(); ++j) points.push_back(pose.position(t, j));
    for (size_t e = 0; e < clip.skeleton.end_sites.size(); ++e) points.push_back(sites[t * clip.skeleton.end_sites.size() + e]);
    for (const Vec3& p : points) {
      const Point pixel = view.project(t, p);
      EXPECT_GE(pixel.x(), t * view.panel_width - 1e-6);
      EXPECT_LE(pixel.x(), (t + 1) * view.panel_width + 1e-6);
      EXPECT_GE(pixel.y(), -1e-6);
      EXPECT_LE(pixel.y(), view.ground_row + 1e-6);
      lowest = std::max(lowest, pixel.y());
    }
  }
  EXPECT_NEAR(lowest, view.ground_row, 1e-6) << "the ground line is the lowest point of the motion";
}

// A biped facing +Z, +Y up: left joints at +X, toes ahead of the ankles.
Clip biped_facing_z() {
  Skeleton s;
  const auto layout = ChannelLayout::rotations(EulerOrder::ZXY);
  const int hips = s.add_joint("Hips", -1, {0, 1.0, 0}, ChannelLayout::position_rotations(EulerOrder::ZXY));
  const int left_leg = s.add_joint("LeftUpLeg", hips, {0.1, 0, 0}, layout);
  const int left_foot = s.add_joint("LeftFoot", left_leg, {0, -0.9, 0}, layout);
  s.add_joint("LeftToe", left_foot, {0, -0.05, 0.15}, layout);
  const int right_leg = s.add_joint("RightUpLeg", hips, {-0.1, 0, 0}, layout);
  const int right_foot = s.add_joint("RightFoot", right_leg, {0, -0.9, 0}, layout);
  s.add_joint("RightToe", right_foot, {0, -0.05, 0.15}, layout);
  s.add_joint("Head", hips, {0, 0.7, 0}, layout);
  Clip clip;
  clip.skeleton = s;
  clip.motion = Motion::rest(s, 3, 30.0);
  for (int t = 0; t < 3; ++t) clip.motion.translation(t, 0) = {0.0, 1.0, 0.2 * t};
  return clip;
}

TEST(Strip, LooksAtTheRightSideWithForwardPointingRight) {
  Clip clip = biped_facing_z();
  StripOptions options;
  options.frames = 1;
  StripView view = plan_strip(clip, options);
  EXPECT_LT((view.forward - Vec3::UnitZ()).norm(), 1e-9) << view.forward.transpose() << " " << view.facing_source;
  EXPECT_LT((view.away - Vec3::UnitX()).norm(), 1e-9) << "the creature's left is away from the camera";
  Pose pose = forward_kinematics(clip.skeleton, clip.motion);
  const int toe = clip.skeleton.find("RightToe"), foot = clip.skeleton.find("RightFoot"), head = clip.skeleton.find("Head");
  EXPECT_GT(view.project(0, pose.position(1, toe)).x(), view.project(0, pose.position(1, foot)).x() + 1.0);
  EXPECT_LT(view.project(0, pose.position(1, head)).y(), view.project(0, pose.position(1, foot)).y() - 10.0);

  // Turned to face +X and stored Z-up: still a side view with the toes to the right and the head up.
  transform_clip(clip, axis_rotation(0, 90.0) * axis_rotation(1, 90.0), 1.0, Vec3::Zero());
  options.up = UpAxis::Z;
  view = plan_strip(clip, options);
  EXPECT_LT((view.forward - Vec3::UnitX()).norm(), 1e-9) << view.forward.transpose();
  pose = forward_kinematics(clip.skeleton, clip.motion);
  EXPECT_GT(view.project(0, pose.position(1, toe)).x(), view.project(0, pose.position(1, foot)).x() + 1.0);
  EXPECT_LT(view.project(0, pose.position(1, head)).y(), view.project(0, pose.position(1, foot)).y() - 10.0);

  options.facing_degrees = -90.0;  // forward = -X: the toes now point left
  view = plan_strip(clip, options);
  EXPECT_EQ(view.facing_source, "option");
  EXPECT_LT(view.project(0, pose.position(1, toe)).x(), view.project(0, pose.position(1, foot)).x() - 1.0);
}

TEST(Strip, RejectsBadOptionsAndEmptyMotions) {
  const Clip clip = biped_facing_z();
  StripOptions options;
  options.frames = 0;
  EXPECT_THROW(plan_strip(clip, options), std::invalid_argument);
  options.frames = 3;
  options.panel_height = 8;
  EXPECT_THROW(plan_strip(clip, options), std::invalid_argument);
  Clip empty = clip;
  empty.motion = Motion::rest(clip.skeleton, 0, 30.0);
  EXPECT_THROW(plan_strip(empty, StripOptions{}), std::invalid_argument);
}

TEST(Strip, StacksRows) {
  const Image stacked = stack_rows({Image(10, 4, {1, 2, 3}), Image(6, 5, {4, 5, 6})});
  EXPECT_EQ(stacked.width, 10);
  EXPECT_EQ(stacked.height, 9);
  EXPECT_EQ(stacked.at(9, 3), Rgb({1, 2, 3}));
  EXPECT_EQ(stacked.at(5, 4), Rgb({4, 5, 6}));
  EXPECT_EQ(stacked.at(9, 8), Rgb({255, 255, 255}));
}

// ---- The HTML page ----

// Text of the <script ... id="ID"> block.
std::string script_text(const std::string& page, const std::string& id) {
  const size_t at = page.find("id=\"" + id + "\"");
  if (at == std::string::npos) return "";
  const size_t open = page.find('>', at) + 1;
  return page.substr(open, page.find("</script>", open) - open);
}

class Page : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nec_viewer_page_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(Page, EmbedsClipsCaptionsAndThreeWithoutNetwork) {
  const std::string cmu = testing::cmu_bvh_dir() + "/01_01.bvh";
  const fs::path copy = dir_ / "jump.bvh";
  fs::copy_file(cmu, copy);
  std::ofstream(dir_ / "jump.txt") << "a person jumps forward\nsomeone hops ahead\n";
  std::vector<ViewClip> clips = {load_view_clip(copy.string()), load_view_clip(cmu)};
  EXPECT_EQ(clips[0].name, "jump");
  EXPECT_EQ(clips[0].captions, (std::vector<std::string>{"a person jumps forward", "someone hops ahead"}));
  clips[1].captions = {"</script><script>alert(1)</script>"};
  ViewOptions options;
  options.title = "two <jumps>";
  options.max_fps = 30;
  if (!have_three()) {
    try {
      make_view_html(clips, options);
      FAIL() << "expected ViewerUnavailable";
    } catch (const ViewerUnavailable& e) {
      EXPECT_NE(std::string(e.what()).find("scripts/setup.sh"), std::string::npos) << e.what();
    }
    GTEST_SKIP() << "three.js was not embedded (run scripts/setup_viewer_assets.sh and rebuild)";
  }
  const std::string page = make_view_html(clips, options);
  EXPECT_EQ(three_version(), "0.170.0");
  EXPECT_NE(page.find("<title>two &lt;jumps&gt;</title>"), std::string::npos);
  EXPECT_EQ(page.find("<script>alert"), std::string::npos) << "caption text must not become markup";
  EXPECT_NE(page.find("MIT License"), std::string::npos);
  // Nothing is fetched: no src/href attributes, no import of a URL.
  EXPECT_EQ(page.find(" src="), std::string::npos);
  EXPECT_EQ(page.find(" href="), std::string::npos);
  // (a comment of GLTFLoader mentions "loaded from 'https://...'": only lines that are no comment count)
  for (size_t at = page.find("from 'http"); at != std::string::npos; at = page.find("from 'http", at + 1)) {
    const size_t begin = page.rfind('\n', at) + 1;
    const std::string line = page.substr(begin, at - begin);
    EXPECT_NE(line.find("//"), std::string::npos) << "an import of a URL: " << line;
  }
  for (const char* id : {"nec-module-three", "nec-module-bvhloader", "nec-module-gltfloader",
                         "nec-module-buffergeometryutils", "nec-module-orbitcontrols", "nec-module-app"}) {
    EXPECT_GT(script_text(page, id).size(), 1000u) << id;
  }
  EXPECT_NE(script_text(page, "nec-module-bvhloader").find("class BVHLoader"), std::string::npos);

  // The clips: JSON description and BVH text that nec reads back as the resampled clip.
  const std::string described = script_text(page, "nec-clips");
  EXPECT_NE(described.find("\"captions\":[\"a person jumps forward\",\"someone hops ahead\"]"), std::string::npos);
  EXPECT_NE(described.find("\\u003c/script>"), std::string::npos) << "'<' is escaped inside the JSON";
  const int frames_at_30 = resample(clips[0].clip.motion, 30.0).frame_count;
  EXPECT_NE(described.find("\"joints\":31"), std::string::npos);
  EXPECT_NE(described.find("\"frames\":" + std::to_string(frames_at_30)), std::string::npos);
  for (const char* id : {"nec-bvh-0", "nec-bvh-1"}) {
    const Clip embedded = parse_bvh(script_text(page, id), id);
    EXPECT_EQ(embedded.skeleton.names, clips[0].clip.skeleton.names);
    EXPECT_EQ(embedded.motion.frame_count, frames_at_30);
    EXPECT_NEAR(embedded.motion.fps, 30.0, 1e-3);
  }
}

TEST_F(Page, TextThatWouldEndTheScriptIsStoredAsBase64) {
  if (!have_three()) GTEST_SKIP() << "three.js was not embedded";
  Clip clip = read_bvh(testing::cmu_bvh_dir() + "/01_01.bvh");
  clip.skeleton.names[1] = "odd</script>name";
  const std::string page = make_view_html({ViewClip{"odd", {}, clip}});
  EXPECT_EQ(page.find("odd</script>name"), std::string::npos);
  const size_t block = page.find("id=\"nec-bvh-0\"");
  ASSERT_NE(block, std::string::npos);
  EXPECT_NE(page.substr(block, 60).find("data-encoding=\"base64\""), std::string::npos);
  EXPECT_THROW(make_view_html({}), std::invalid_argument);
}

}  // namespace
}  // namespace nec::viewer
