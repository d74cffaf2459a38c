#include "tracer/image.h"

#include <algorithm>
#include <cmath>

#include "accel/core/error.h"
#include "datasets/atomic_file.h"

// The one definition of stb_image_write and stb_image in the project.
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_PNG
#include <stb/stb_image.h>

namespace ab {

void Image8::set(int x, int y, uint8_t r, uint8_t g, uint8_t b) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  uint8_t* p = &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3];
  p[0] = r;
  p[1] = g;
  p[2] = b;
}

namespace {
uint8_t encode_srgb(float v) {
  if (!(v > 0.0f)) return 0;  // also NaN
  v = std::min(v, 1.0f);
  const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(s * 255.0f));
}

void append_bytes(void* context, void* data, int size) {
  auto* out = static_cast<std::string*>(context);
  out->append(static_cast<const char*>(data), static_cast<size_t>(size));
}
}  // namespace

Image8 to_srgb8(const Image& image) {
  Image8 out(image.width, image.height);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    for (int k = 0; k < 3; ++k) out.rgb[3 * i + size_t(k)] = encode_srgb(image.pixels[i][k]);
  return out;
}

void write_png(const Image8& image, const std::string& path) {
  std::string bytes;
  if (!stbi_write_png_to_func(append_bytes, &bytes, image.width, image.height, 3, image.rgb.data(),
                              image.width * 3))
    throw InputError(path + ": cannot encode PNG");
  write_file_atomically(path,
                        [&](std::ostream& os) { os.write(bytes.data(), std::streamsize(bytes.size())); });
}

Image8 read_png(const std::string& path) {
  int w = 0, h = 0, channels = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &channels, 3);
  if (!data) throw InputError(path + ": cannot read PNG (" + std::string(stbi_failure_reason()) + ")");
  Image8 out(w, h);
  std::copy(data, data + size_t(w) * size_t(h) * 3, out.rgb.begin());
  stbi_image_free(data);
  return out;
}

}  // namespace ab
