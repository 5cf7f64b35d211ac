#include "common/rgb_image.h"

#include <cairo.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <system_error>

namespace graspbed::image {
namespace {

struct SurfaceDeleter {
  void operator()(cairo_surface_t* surface) const { cairo_surface_destroy(surface); }
};
using Surface = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;

}  // namespace

void WritePng(const RgbImage& image, const std::string& path) {
  if (image.width_px <= 0 || image.height_px <= 0 ||
      image.rgb.size() != static_cast<size_t>(image.width_px) * image.height_px * 3) {
    throw std::invalid_argument("image " + path + ": " + std::to_string(image.width_px) + "x" +
                                std::to_string(image.height_px) + " with " +
                                std::to_string(image.rgb.size()) + " bytes: not a non-empty RGB image");
  }
  Surface surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, image.width_px, image.height_px));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error("image " + path + ": " +
                             cairo_status_to_string(cairo_surface_status(surface.get())));
  }
  // CAIRO_FORMAT_RGB24: one native-endian uint32 per pixel, 0x00RRGGBB.
  cairo_surface_flush(surface.get());
  unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  for (int row = 0; row < image.height_px; ++row) {
    auto* out = reinterpret_cast<uint32_t*>(data + static_cast<size_t>(row) * stride);
    for (int column = 0; column < image.width_px; ++column) {
      const uint8_t* p = image.At(column, row);
      out[column] = (uint32_t{p[0]} << 16) | (uint32_t{p[1]} << 8) | uint32_t{p[2]};
    }
  }
  cairo_surface_mark_dirty(surface.get());

  static std::atomic<uint64_t> counter{0};
  const std::string temp_path = path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  const cairo_status_t status = cairo_surface_write_to_png(surface.get(), temp_path.c_str());
  std::error_code ignored;
  if (status != CAIRO_STATUS_SUCCESS) {
    std::filesystem::remove(temp_path, ignored);
    throw std::runtime_error("cannot write " + path + ": " + cairo_status_to_string(status));
  }
  std::error_code error;
  std::filesystem::rename(temp_path, path, error);
  if (error) {
    std::filesystem::remove(temp_path, ignored);
    throw std::runtime_error("cannot write " + path + ": " + error.message());
  }
}

RgbImage ReadPng(const std::string& path) {
  Surface surface(cairo_image_surface_create_from_png(path.c_str()));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error("cannot read " + path + ": " +
                             cairo_status_to_string(cairo_surface_status(surface.get())));
  }
  const cairo_format_t format = cairo_image_surface_get_format(surface.get());
  if (format != CAIRO_FORMAT_RGB24 && format != CAIRO_FORMAT_ARGB32) {
    throw std::runtime_error("cannot read " + path + ": not an 8-bit RGB(A) PNG");
  }
  RgbImage image;
  image.width_px = cairo_image_surface_get_width(surface.get());
  image.height_px = cairo_image_surface_get_height(surface.get());
  image.rgb.resize(static_cast<size_t>(image.width_px) * image.height_px * 3);
  cairo_surface_flush(surface.get());
  const unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  for (int row = 0; row < image.height_px; ++row) {
    const auto* in = reinterpret_cast<const uint32_t*>(data + static_cast<size_t>(row) * stride);
    for (int column = 0; column < image.width_px; ++column) {
      // ARGB32 is premultiplied; opaque pixels (all that WritePng makes) are unchanged by that.
      uint8_t* p = image.rgb.data() + 3 * (static_cast<size_t>(row) * image.width_px + column);
      p[0] = static_cast<uint8_t>(in[column] >> 16);
      p[1] = static_cast<uint8_t>(in[column] >> 8);
      p[2] = static_cast<uint8_t>(in[column]);
    }
  }
  return image;
}

}  // namespace graspbed::image
