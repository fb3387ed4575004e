#pragma once
// Pixel classification shared by the render and view tests: what a pixel shows, by the palette's families
// (render/renderer.hpp), and whether a world point's pixel shows what it should.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include <drench/render/camera.hpp>
#include <drench/render/png_image.hpp>

namespace drench::render {

/// What a pixel shows, by the palette's families (renderer.hpp): the cloth is red over blue, the water blue
/// over red, the backdrop a light grey. Ratios, not differences, so that a side in shadow classifies too.
enum class ColourClass { BACKDROP, CLOTH, WATER, OTHER };

inline const char* name(ColourClass c) {
  switch (c) {
    case ColourClass::BACKDROP:
      return "backdrop";
    case ColourClass::CLOTH:
      return "cloth";
    case ColourClass::WATER:
      return "water";
    default:
      return "other";
  }
}

inline ColourClass classify(const std::array<std::uint8_t, 3>& p) {
  const int r = p[0], g = p[1], b = p[2];
  if (r > 40 && 10 * r > 16 * b && 10 * r > 13 * g) return ColourClass::CLOTH;
  if (b > 40 && 10 * b > 16 * r) return ColourClass::WATER;
  if (std::max({r, g, b}) - std::min({r, g, b}) < 12 && std::min({r, g, b}) > 150)
    return ColourClass::BACKDROP;
  return ColourClass::OTHER;
}

/// The colour class of the pixel `point` projects to; fails the test when it is outside the image.
inline testing::AssertionResult shows(const Image& image, const Camera& camera, const Vec3& point,
                                      ColourClass expected) {
  const auto pixel = project_to_pixel(camera, image.width, image.height, point);
  if (!pixel) return testing::AssertionFailure() << "point is behind the camera";
  const int x = static_cast<int>(std::floor(pixel->x())), y = static_cast<int>(std::floor(pixel->y()));
  if (x < 0 || y < 0 || x >= image.width || y >= image.height)
    return testing::AssertionFailure() << "point projects outside the image, to (" << x << ", " << y << ")";
  const auto rgb = image.at(x, y);
  const ColourClass actual = classify(rgb);
  if (actual == expected) return testing::AssertionSuccess();
  return testing::AssertionFailure() << "pixel (" << x << ", " << y << ") is " << name(actual) << " (rgb "
                                     << int(rgb[0]) << " " << int(rgb[1]) << " " << int(rgb[2])
                                     << "), expected " << name(expected);
}

/// Whether some pixel in the square of `radius` pixels about where `point` projects shows `expected`: for
/// particles, drawn a few pixels wide with gaps between them. Fails when the point is outside the image.
inline testing::AssertionResult shows_near(const Image& image, const Camera& camera, const Vec3& point,
                                           ColourClass expected, int radius) {
  const auto pixel = project_to_pixel(camera, image.width, image.height, point);
  if (!pixel) return testing::AssertionFailure() << "point is behind the camera";
  const int x0 = static_cast<int>(std::floor(pixel->x())), y0 = static_cast<int>(std::floor(pixel->y()));
  if (x0 - radius < 0 || y0 - radius < 0 || x0 + radius >= image.width || y0 + radius >= image.height)
    return testing::AssertionFailure() << "the square about (" << x0 << ", " << y0 << ") leaves the image";
  for (int y = y0 - radius; y <= y0 + radius; ++y) {
    for (int x = x0 - radius; x <= x0 + radius; ++x) {
      if (classify(image.at(x, y)) == expected) return testing::AssertionSuccess();
    }
  }
  return testing::AssertionFailure() << "no pixel within " << radius << " of (" << x0 << ", " << y0 << ") is "
                                     << name(expected);
}

}  // namespace drench::render
