#include "tracer/heatmap.h"

#include <stb/stb_easy_font.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ab {

void viridis(float t, uint8_t rgb[3]) {
  static constexpr uint8_t kStops[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                           {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                           {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
  t = std::clamp(t, 0.0f, 1.0f) * 8.0f;
  const int i = std::min(7, static_cast<int>(t));
  const float f = t - float(i);
  for (int k = 0; k < 3; ++k)
    rgb[k] =
        static_cast<uint8_t>(std::lround(float(kStops[i][k]) * (1.0f - f) + float(kStops[i + 1][k]) * f));
}

namespace {

/// Draws text with stb_easy_font (quads of one colour) at (x, y), scaled by an integer factor.
void draw_text(Image8& img, int x, int y, const std::string& text, int scale, uint8_t grey) {
  static char buffer[60000];
  const int quads =
      stb_easy_font_print(0.0f, 0.0f, const_cast<char*>(text.c_str()), nullptr, buffer, sizeof buffer);
  const auto* v = reinterpret_cast<const float*>(buffer);
  for (int q = 0; q < quads; ++q) {
    const float* p = v + q * 16;  // 4 vertices of (x, y, z, colour) = 4 floats each
    const int x0 = static_cast<int>(p[0]), y0 = static_cast<int>(p[1]);
    const int x1 = static_cast<int>(p[8]), y1 = static_cast<int>(p[9]);
    for (int yy = y0 * scale; yy < y1 * scale; ++yy)
      for (int xx = x0 * scale; xx < x1 * scale; ++xx) img.set(x + xx, y + yy, grey, grey, grey);
  }
}

int text_width(const std::string& text, int scale) {
  return stb_easy_font_width(const_cast<char*>(text.c_str())) * scale;
}

std::string number_label(float v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, v >= 100.0f || v == std::floor(v) ? "%.0f" : "%.1f", double(v));
  return buf;
}

}  // namespace

Image8 heatmap_image(const std::vector<float>& values, int width, int height, const std::string& label,
                     float scale_max) {
  const int scale = width >= 384 ? 2 : 1;
  const int bar_h = 10 * scale, text_h = 24 * scale, margin = 4 * scale;
  Image8 img(width, height + margin + bar_h + text_h + margin);
  std::fill(img.rgb.begin() + std::ptrdiff_t(size_t(width) * size_t(height) * 3), img.rgb.end(),
            uint8_t(255));
  float vmax = 0.0f;
  for (float v : values) vmax = std::max(vmax, v);
  if (scale_max > 0.0f) vmax = scale_max;
  const float denom = vmax > 0.0f ? vmax : 1.0f;
  uint8_t c[3];
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      viridis(values[size_t(y) * size_t(width) + size_t(x)] / denom, c);
      img.set(x, y, c[0], c[1], c[2]);
    }
  const int x0 = margin, x1 = width - margin, bar_y = height + margin;
  for (int x = x0; x < x1; ++x) {
    viridis(float(x - x0) / float(std::max(1, x1 - x0 - 1)), c);
    for (int y = bar_y; y < bar_y + bar_h; ++y) img.set(x, y, c[0], c[1], c[2]);
  }
  const int ty = bar_y + bar_h + 2 * scale;
  draw_text(img, x0, ty, "0", scale, 0);
  const std::string mid = number_label(vmax / 2.0f), hi = number_label(vmax);
  draw_text(img, (x0 + x1 - text_width(mid, scale)) / 2, ty, mid, scale, 0);
  draw_text(img, x1 - text_width(hi, scale), ty, hi, scale, 0);
  draw_text(img, (x0 + x1 - text_width(label, scale)) / 2, ty + 11 * scale, label, scale, 80);
  return img;
}

}  // namespace ab
