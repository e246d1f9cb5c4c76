// PNG writing with nothing but the standard library: CRC-32, Adler-32, a zlib
// stream (LZ77 + fixed-Huffman deflate, or stored blocks) and the PNG chunks.
//
//   Image image(640, 320, {255, 255, 255});
//   image.at(10, 20) = {200, 30, 30};
//   write_png("strip.png", image);          // atomic, throws std::runtime_error
//
// Output is 8-bit RGB, non-interlaced; every row gets the filter (None, Sub,
// Up, Average, Paeth) with the smallest sum of absolute differences.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace nec::viewer {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& other) const { return r == other.r && g == other.g && b == other.b; }
  bool operator!=(const Rgb& other) const { return !(*this == other); }
};

// An 8-bit RGB raster, rows top to bottom.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<Rgb> pixels;  // (height, width)

  Image() = default;
  Image(int width_pixels, int height_pixels, Rgb fill = {255, 255, 255});
  Rgb& at(int x, int y) { return pixels[static_cast<size_t>(y) * width + x]; }
  const Rgb& at(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
  bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
};

// CRC-32 as in PNG and zlib (polynomial 0xEDB88320); pass the previous value to continue.
std::uint32_t crc32(std::string_view bytes, std::uint32_t crc = 0);
// Adler-32 as in zlib; pass the previous value to continue (start: 1).
std::uint32_t adler32(std::string_view bytes, std::uint32_t adler = 1);

enum class Deflate { Stored, FixedHuffman };
// A zlib stream (RFC 1950) holding `data`: stored blocks, or one LZ77 block
// with the fixed Huffman codes of RFC 1951.
std::string zlib_compress(std::string_view data, Deflate method = Deflate::FixedHuffman);

// The PNG file of `image`; throws std::invalid_argument for an empty image.
std::string encode_png(const Image& image, Deflate method = Deflate::FixedHuffman);
void write_png(const std::string& path, const Image& image);

}  // namespace nec::viewer
