#pragma once
/// An 8-bit RGB picture in memory (rows from the top) and its PNG file (libpng), for plots and stills.
/// Files are written atomically (temporary file + rename), so a reader never sees half a PNG.

#include <cstdint>
#include <string>
#include <vector>

namespace graspbed::image {

/// width x height pixels, 3 bytes (R, G, B) each, row-major from the top-left corner.
struct RgbImage {
  int width_px = 0;
  int height_px = 0;
  std::vector<uint8_t> rgb;  ///< width_px * height_px * 3 bytes

  /// Pointer to the R byte of pixel (`column`, `row`), row 0 at the top; no bounds check.
  const uint8_t* At(int column, int row) const {
    return rgb.data() + 3 * (static_cast<size_t>(row) * width_px + column);
  }
};

/// Writes `image` as a PNG at `path` (temp file + rename). Throws std::invalid_argument for an empty
/// image or a buffer whose size does not match, std::runtime_error naming the path when the file cannot
/// be written.
void WritePng(const RgbImage& image, const std::string& path);

/// Reads a PNG (any of its colour types and depths, converted to 8-bit RGB). Throws std::runtime_error naming
/// the path when the file is missing or not a PNG.
RgbImage ReadPng(const std::string& path);

}  // namespace graspbed::image
