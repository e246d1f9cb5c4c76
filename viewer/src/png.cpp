// PNG encoder: checksums, a small deflate (LZ77 with hash chains, fixed
// Huffman codes) and the PNG chunk layout.
#include "nec/viewer/png.h"

#include "nec/motion/files.h"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <stdexcept>

namespace nec::viewer {
namespace {

// Writes bits least significant first, as deflate packs them.
class BitWriter {
 public:
  explicit BitWriter(std::string& out) : out_(out) {}
  void put(std::uint32_t value, int bits) {
    buffer_ |= static_cast<std::uint64_t>(value) << count_;
    count_ += bits;
    while (count_ >= 8) {
      out_.push_back(static_cast<char>(buffer_ & 0xFF));
      buffer_ >>= 8;
      count_ -= 8;
    }
  }
  // Huffman codes are defined most significant bit first.
  void put_code(std::uint32_t code, int bits) {
    std::uint32_t reversed = 0;
    for (int i = 0; i < bits; ++i) reversed |= ((code >> i) & 1u) << (bits - 1 - i);
    put(reversed, bits);
  }
  void flush() {
    if (count_ > 0) out_.push_back(static_cast<char>(buffer_ & 0xFF));
    buffer_ = 0;
    count_ = 0;
  }

 private:
  std::string& out_;
  std::uint64_t buffer_ = 0;
  int count_ = 0;
};

constexpr std::array<int, 29> kLengthBase = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                             31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
constexpr std::array<int, 29> kLengthExtra = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                              2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
constexpr std::array<int, 30> kDistanceBase = {1,   2,   3,   4,   5,   7,    9,    13,   17,   25,
                                               33,  49,  65,  97,  129, 193,  257,  385,  513,  769,
                                               1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
constexpr std::array<int, 30> kDistanceExtra = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                                                6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

// Literal/length symbol in the fixed Huffman code (RFC 1951 3.2.6).
void put_fixed_symbol(BitWriter& bits, int symbol) {
  if (symbol < 144) {
    bits.put_code(0x30 + symbol, 8);
  } else if (symbol < 256) {
    bits.put_code(0x190 + symbol - 144, 9);
  } else if (symbol < 280) {
    bits.put_code(symbol - 256, 7);
  } else {
    bits.put_code(0xC0 + symbol - 280, 8);
  }
}

void put_match(BitWriter& bits, int length, int distance) {
  int l = static_cast<int>(std::upper_bound(kLengthBase.begin(), kLengthBase.end(), length) - kLengthBase.begin()) - 1;
  put_fixed_symbol(bits, 257 + l);
  if (kLengthExtra[l] > 0) bits.put(length - kLengthBase[l], kLengthExtra[l]);
  int d = static_cast<int>(std::upper_bound(kDistanceBase.begin(), kDistanceBase.end(), distance) -
                           kDistanceBase.begin()) - 1;
  bits.put_code(d, 5);
  if (kDistanceExtra[d] > 0) bits.put(distance - kDistanceBase[d], kDistanceExtra[d]);
}

void deflate_fixed(std::string_view data, std::string& out) {
  constexpr int kWindow = 32768;      // largest deflate distance
  constexpr int kMinMatch = 3;
  constexpr int kMaxMatch = 258;
  constexpr int kHashBits = 15;
  constexpr int kMaxChain = 64;       // candidates tried per position
  const int n = static_cast<int>(data.size());
  const auto byte = [&](int i) { return static_cast<std::uint32_t>(static_cast<unsigned char>(data[i])); };
  const auto hash = [&](int i) {
    return ((byte(i) << 10) ^ (byte(i + 1) << 5) ^ byte(i + 2)) & ((1u << kHashBits) - 1);
  };
  std::vector<int> head(1u << kHashBits, -1);
  std::vector<int> previous(kWindow, -1);  // previous position with the same hash, by position % window
  const auto insert = [&](int i) {
    if (i + kMinMatch > n) return;
    const std::uint32_t h = hash(i);
    previous[i & (kWindow - 1)] = head[h];
    head[h] = i;
  };

  BitWriter bits(out);
  bits.put(1, 1);  // final block
  bits.put(1, 2);  // fixed Huffman codes
  int pos = 0;
  while (pos < n) {
    int best_length = 0, best_distance = 0;
    if (pos + kMinMatch <= n) {
      const int limit = std::min(kMaxMatch, n - pos);
      int candidate = head[hash(pos)];
      for (int chain = 0; candidate >= 0 && pos - candidate <= kWindow && chain < kMaxChain; ++chain) {
        int length = 0;
        while (length < limit && data[candidate + length] == data[pos + length]) ++length;
        if (length > best_length) {
          best_length = length;
          best_distance = pos - candidate;
          if (length == limit) break;
        }
        const int next = previous[candidate & (kWindow - 1)];
        if (next >= candidate) break;  // slot reused by a newer position: the chain ends here
        candidate = next;
      }
    }
    if (best_length >= kMinMatch) {
      put_match(bits, best_length, best_distance);
      for (int i = 0; i < best_length; ++i) insert(pos + i);
      pos += best_length;
    } else {
      put_fixed_symbol(bits, byte(pos));
      insert(pos);
      ++pos;
    }
  }
  put_fixed_symbol(bits, 256);  // end of block
  bits.flush();
}

void deflate_stored(std::string_view data, std::string& out) {
  constexpr size_t kMaxBlock = 65535;
  size_t offset = 0;
  do {
    const size_t length = std::min(kMaxBlock, data.size() - offset);
    const bool final = offset + length == data.size();
    BitWriter bits(out);
    bits.put(final ? 1 : 0, 1);
    bits.put(0, 2);  // stored
    bits.flush();
    out.push_back(static_cast<char>(length & 0xFF));
    out.push_back(static_cast<char>(length >> 8));
    out.push_back(static_cast<char>(~length & 0xFF));
    out.push_back(static_cast<char>((~length >> 8) & 0xFF));
    out.append(data.substr(offset, length));
    offset += length;
  } while (offset < data.size());
}

void put_u32_be(std::string& out, std::uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((value >> shift) & 0xFF));
}

void put_chunk(std::string& png, const char* type, std::string_view data) {
  put_u32_be(png, static_cast<std::uint32_t>(data.size()));
  const size_t start = png.size();
  png.append(type, 4);
  png.append(data);
  put_u32_be(png, crc32(std::string_view(png).substr(start)));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

// Scanlines, each prefixed by the filter type that makes it cheapest to compress.
std::string filtered_scanlines(const Image& image) {
  constexpr int kBytesPerPixel = 3;
  const size_t stride = static_cast<size_t>(image.width) * kBytesPerPixel;
  std::vector<unsigned char> previous(stride, 0), current(stride);
  std::array<std::vector<unsigned char>, 5> candidates;
  for (auto& c : candidates) c.resize(stride);
  std::string out;
  out.reserve((stride + 1) * image.height);
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const Rgb& p = image.at(x, y);
      current[x * 3] = p.r;
      current[x * 3 + 1] = p.g;
      current[x * 3 + 2] = p.b;
    }
    int best = 0;
    long best_cost = -1;
    for (int type = 0; type < 5; ++type) {
      long cost = 0;
      for (size_t i = 0; i < stride; ++i) {
        const int a = i >= kBytesPerPixel ? current[i - kBytesPerPixel] : 0;
        const int b = previous[i];
        const int c = i >= kBytesPerPixel ? previous[i - kBytesPerPixel] : 0;
        const int predictor = type == 0 ? 0 : type == 1 ? a : type == 2 ? b : type == 3 ? (a + b) / 2 : paeth(a, b, c);
        const auto value = static_cast<unsigned char>(current[i] - predictor);
        candidates[type][i] = value;
        cost += std::abs(static_cast<int>(static_cast<signed char>(value)));
      }
      if (best_cost < 0 || cost < best_cost) {
        best_cost = cost;
        best = type;
      }
    }
    out.push_back(static_cast<char>(best));
    out.append(reinterpret_cast<const char*>(candidates[best].data()), stride);
    std::swap(previous, current);
  }
  return out;
}

}  // namespace

Image::Image(int width_pixels, int height_pixels, Rgb fill)
    : width(width_pixels), height(height_pixels),
      pixels(static_cast<size_t>(std::max(0, width_pixels)) * std::max(0, height_pixels), fill) {}

std::uint32_t crc32(std::string_view bytes, std::uint32_t crc) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n) {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (char ch : bytes) crc = table[(crc ^ static_cast<unsigned char>(ch)) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

std::uint32_t adler32(std::string_view bytes, std::uint32_t adler) {
  constexpr std::uint32_t kModulus = 65521;
  constexpr size_t kMaxRun = 5552;  // longest run before the sums can overflow 32 bits
  std::uint32_t a = adler & 0xFFFF, b = adler >> 16;
  while (!bytes.empty()) {
    const size_t run = std::min(kMaxRun, bytes.size());
    for (size_t i = 0; i < run; ++i) {
      a += static_cast<unsigned char>(bytes[i]);
      b += a;
    }
    a %= kModulus;
    b %= kModulus;
    bytes.remove_prefix(run);
  }
  return (b << 16) | a;
}

std::string zlib_compress(std::string_view data, Deflate method) {
  std::string out;
  out.push_back(static_cast<char>(0x78));  // deflate, 32 KiB window
  out.push_back(static_cast<char>(0x01));  // no preset dictionary; (0x78 << 8 | 0x01) % 31 == 0
  if (method == Deflate::Stored) {
    deflate_stored(data, out);
  } else {
    deflate_fixed(data, out);
  }
  put_u32_be(out, adler32(data));
  return out;
}

std::string encode_png(const Image& image, Deflate method) {
  if (image.width <= 0 || image.height <= 0 || image.pixels.size() != static_cast<size_t>(image.width) * image.height) {
    throw std::invalid_argument("encode_png: image is empty or its pixel count does not match its size");
  }
  std::string png = "\x89PNG\r\n\x1a\n";
  std::string header;
  put_u32_be(header, static_cast<std::uint32_t>(image.width));
  put_u32_be(header, static_cast<std::uint32_t>(image.height));
  header += std::string("\x08\x02\x00\x00\x00", 5);  // 8 bits, RGB, deflate, adaptive filters, no interlace
  put_chunk(png, "IHDR", header);
  put_chunk(png, "IDAT", zlib_compress(filtered_scanlines(image), method));
  put_chunk(png, "IEND", "");
  return png;
}

void write_png(const std::string& path, const Image& image) { write_file_atomic(path, encode_png(image)); }

}  // namespace nec::viewer
