// Anti-aliased drawing into an Image: thick line segments with round caps,
// discs, rectangles and a 5x7 pixel font for short labels.
//
//   Image image(400, 300);
//   draw_segment(image, {20, 280}, {200, 40}, 2.5, {40, 40, 60});   // radius in pixels
//   draw_disc(image, {200, 40}, 4.0, {200, 60, 40});
//   draw_text(image, 8, 8, "frame 120  1.00 s", 2, {90, 90, 90});
//
// Coordinates are pixels with (0, 0) the top-left corner of the top-left
// pixel, so pixel (x, y) covers [x, x+1) x [y, y+1) and its centre is
// (x + 0.5, y + 0.5). Edges are blended by the covered fraction of a pixel
// (approximated from the distance of its centre to the shape).
#pragma once

#include "nec/viewer/png.h"

#include <Eigen/Core>

#include <string_view>

namespace nec::viewer {

using Point = Eigen::Vector2d;  // pixels, x right, y down

// a + (b - a) * t per channel, t in [0, 1].
Rgb mix(const Rgb& a, const Rgb& b, double t);
// Blends `color` over pixel (x, y) with opacity `alpha` in [0, 1]; outside the image does nothing.
void blend_pixel(Image& image, int x, int y, const Rgb& color, double alpha);

// The capsule of all points within `radius` of segment ab.
void draw_segment(Image& image, const Point& a, const Point& b, double radius, const Rgb& color);
void draw_disc(Image& image, const Point& center, double radius, const Rgb& color);
// Pixels [x0, x1) x [y0, y1), clipped to the image.
void fill_rect(Image& image, int x0, int y0, int x1, int y1, const Rgb& color);

// Text in a 5x7 font, each font pixel a `scale` x `scale` block, top-left at
// (x, y), 6 * scale pixels per character. Knows the digits, space and
// . : - / # = a e f m r s t; other characters are left blank.
void draw_text(Image& image, int x, int y, std::string_view text, int scale, const Rgb& color);
int text_width(std::string_view text, int scale);

}  // namespace nec::viewer
