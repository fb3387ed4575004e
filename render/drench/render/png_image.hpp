#pragma once
/// RGB images and their PNG files, through libpng: what `drench render` writes and its tests read back.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace drench::render {

/// An 8-bit RGB image, rows from the top down (as PNG stores them), pixels left to right.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< 3 * width * height bytes

  /// The pixel in column `x`, row `y` (0 is the top row); 0 <= x < width, 0 <= y < height.
  std::array<std::uint8_t, 3> at(int x, int y) const {
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
};

/// `image` as the bytes of a PNG file (8-bit RGB, no interlace). The fastest zlib level: a frame of
/// 1280 x 720 compresses in a few tens of milliseconds instead of a few hundred, and is still lossless.
/// @throws drench::IoError when libpng fails (with its message) or the image's size is 0 or disagrees with
///         its bytes.
std::string encode_png(const Image& image);

/// Reads a PNG file as 8-bit RGB (palette, grey and 16-bit files are converted; alpha is dropped).
/// @throws drench::IoError naming `path`: the file cannot be read or is not a PNG libpng can decode.
Image read_png(const std::string& path);

}  // namespace drench::render
