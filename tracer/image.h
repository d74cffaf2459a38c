// Images: linear RGB radiance from the integrator, 8-bit sRGB for files, PNG I/O (stb).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "accel/core/aabb.h"

namespace ab {

/// Linear RGB, row-major from the top-left pixel.
struct Image {
  int width = 0, height = 0;
  std::vector<vec3> pixels;

  Image() = default;
  /// A black image.
  Image(int w, int h) : width(w), height(h), pixels(size_t(w) * size_t(h), vec3(0.0f)) {}
  /// Pixel (x, y).
  vec3& at(int x, int y) { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
  /// Pixel (x, y).
  const vec3& at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

/// 8-bit RGB, row-major from the top-left pixel.
struct Image8 {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  ///< 3 bytes per pixel

  Image8() = default;
  /// A black image.
  Image8(int w, int h) : width(w), height(h), rgb(size_t(w) * size_t(h) * 3, 0) {}
  /// Sets pixel (x, y) (ignored outside the image).
  void set(int x, int y, uint8_t r, uint8_t g, uint8_t b);
};

/// Clamps to [0,1] and encodes with the sRGB curve.
Image8 to_srgb8(const Image& image);
/// Writes a PNG whole or not at all (temporary file, renamed). Throws InputError naming the path.
void write_png(const Image8& image, const std::string& path);
/// Reads a PNG as 8-bit RGB. Throws InputError naming the path.
Image8 read_png(const std::string& path);

}  // namespace ab
