#include "common/rgb_image.h"

#include <png.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace graspbed::image {
namespace {

// Frees libpng's state for a simplified-API image on every way out.
struct PngImageGuard {
  png_image* image;
  ~PngImageGuard() { png_image_free(image); }
};

}  // namespace

void WritePng(const RgbImage& image, const std::string& path) {
  if (image.width_px <= 0 || image.height_px <= 0 ||
      image.rgb.size() != static_cast<size_t>(image.width_px) * image.height_px * 3) {
    throw std::invalid_argument("image " + path + ": " + std::to_string(image.width_px) + "x" +
                                std::to_string(image.height_px) + " with " +
                                std::to_string(image.rgb.size()) + " bytes: not a non-empty RGB image");
  }
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width_px);
  png.height = static_cast<png_uint_32>(image.height_px);
  png.format = PNG_FORMAT_RGB;
  // Speed over size: no row filters and light deflate. Encoding with libpng's defaults (every filter
  // tried per row, zlib level 6) took two thirds of a default scenario run's process time for its
  // eight plots; these files are about a quarter larger.
  png.flags = PNG_IMAGE_FLAG_FAST;
  PngImageGuard guard{&png};

  static std::atomic<uint64_t> counter{0};
  const std::string temp_path = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  std::error_code ignored;
  if (png_image_write_to_file(&png, temp_path.c_str(), 0, image.rgb.data(), 0, nullptr) == 0) {
    std::filesystem::remove(temp_path, ignored);
    throw std::runtime_error("cannot write " + path + ": " + png.message);
  }
  std::error_code error;
  std::filesystem::rename(temp_path, path, error);
  if (error) {
    std::filesystem::remove(temp_path, ignored);
    throw std::runtime_error("cannot write " + path + ": " + error.message());
  }
}

RgbImage ReadPng(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  PngImageGuard guard{&png};
  if (png_image_begin_read_from_file(&png, path.c_str()) == 0) {
    throw std::runtime_error("cannot read " + path + ": " + png.message);
  }
  // Any PNG is converted to 8-bit RGB; opaque pixels (all that WritePng makes) read back unchanged.
  png.format = PNG_FORMAT_RGB;
  RgbImage image;
  image.width_px = static_cast<int>(png.width);
  image.height_px = static_cast<int>(png.height);
  image.rgb.resize(PNG_IMAGE_SIZE(png));
  if (png_image_finish_read(&png, nullptr, image.rgb.data(), 0, nullptr) == 0) {
    throw std::runtime_error("cannot read " + path + ": " + png.message);
  }
  return image;
}

}  // namespace graspbed::image
