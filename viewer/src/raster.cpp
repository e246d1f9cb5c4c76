// Anti-aliased rasterization of segments and discs by coverage, and a tiny bitmap font.
#include "nec/viewer/raster.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace nec::viewer {
namespace {

// Covered fraction of a pixel whose centre lies `distance` from a shape of
// half-width `radius`: a one-pixel ramp centred on the edge.
double coverage(double distance, double radius) { return std::clamp(radius + 0.5 - distance, 0.0, 1.0); }

double distance_to_segment(const Point& p, const Point& a, const Point& b) {
  const Point ab = b - a;
  const double length_squared = ab.squaredNorm();
  const double t = length_squared > 0.0 ? std::clamp((p - a).dot(ab) / length_squared, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

struct Glyph {
  char character;
  std::array<unsigned char, 7> rows;  // 5 bits per row, most significant bit = leftmost pixel
};

constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}}, {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'#', {0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A}}, {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'a', {0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F}}, {'e', {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}},
    {'f', {0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08}}, {'m', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11}},
    {'r', {0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10}}, {'s', {0x00, 0x00, 0x0E, 0x10, 0x0E, 0x01, 0x1E}},
    {'t', {0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06}},
};

const Glyph* find_glyph(char c) {
  for (const Glyph& g : kFont) {
    if (g.character == c) return &g;
  }
  return nullptr;
}

}  // namespace

Rgb mix(const Rgb& a, const Rgb& b, double t) {
  const auto channel = [t](int from, int to) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(from + (to - from) * t, 0.0, 255.0)));
  };
  return {channel(a.r, b.r), channel(a.g, b.g), channel(a.b, b.b)};
}

void blend_pixel(Image& image, int x, int y, const Rgb& color, double alpha) {
  if (!image.contains(x, y) || alpha <= 0.0) return;
  Rgb& pixel = image.at(x, y);
  pixel = mix(pixel, color, std::min(alpha, 1.0));
}

void draw_segment(Image& image, const Point& a, const Point& b, double radius, const Rgb& color) {
  const int x0 = static_cast<int>(std::floor(std::min(a.x(), b.x()) - radius - 1.0));
  const int x1 = static_cast<int>(std::ceil(std::max(a.x(), b.x()) + radius + 1.0));
  const int y0 = static_cast<int>(std::floor(std::min(a.y(), b.y()) - radius - 1.0));
  const int y1 = static_cast<int>(std::ceil(std::max(a.y(), b.y()) + radius + 1.0));
  for (int y = std::max(0, y0); y <= std::min(image.height - 1, y1); ++y) {
    for (int x = std::max(0, x0); x <= std::min(image.width - 1, x1); ++x) {
      blend_pixel(image, x, y, color, coverage(distance_to_segment({x + 0.5, y + 0.5}, a, b), radius));
    }
  }
}

void draw_disc(Image& image, const Point& center, double radius, const Rgb& color) {
  draw_segment(image, center, center, radius, color);
}

void fill_rect(Image& image, int x0, int y0, int x1, int y1, const Rgb& color) {
  for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y) {
    for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x) image.at(x, y) = color;
  }
}

void draw_text(Image& image, int x, int y, std::string_view text, int scale, const Rgb& color) {
  for (size_t i = 0; i < text.size(); ++i) {
    const Glyph* glyph = find_glyph(text[i]);
    if (!glyph) continue;
    const int left = x + static_cast<int>(i) * 6 * scale;
    for (int row = 0; row < 7; ++row) {
      for (int column = 0; column < 5; ++column) {
        if (!((glyph->rows[row] >> (4 - column)) & 1)) continue;
        fill_rect(image, left + column * scale, y + row * scale, left + (column + 1) * scale, y + (row + 1) * scale,
                  color);
      }
    }
  }
}

int text_width(std::string_view text, int scale) {
  return text.empty() ? 0 : (static_cast<int>(text.size()) * 6 - 1) * scale;
}

}  // namespace nec::viewer
