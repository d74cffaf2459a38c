#include "accel/core/clip.h"

#include <cmath>

namespace ab {

void clip_polygon(ClipPolygon& poly, const vec3& normal, float offset) {
  if (poly.n == 0) return;
  ClipPolygon out;
  for (int i = 0; i < poly.n; ++i) {
    const vec3& a = poly.v[i];
    const vec3& b = poly.v[(i + 1) % poly.n];
    const float da = glm::dot(normal, a) - offset;
    const float db = glm::dot(normal, b) - offset;
    if (da <= 0.0f && out.n < static_cast<int>(out.v.size())) out.v[out.n++] = a;
    if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {
      const float s = da / (da - db);
      if (out.n < static_cast<int>(out.v.size())) out.v[out.n++] = a + s * (b - a);
    }
  }
  poly = out;
}

void clip_polygon_to_box(ClipPolygon& poly, const AABB& box) {
  for (int a = 0; a < 3 && poly.n > 0; ++a) {
    vec3 axis(0.0f);
    axis[a] = 1.0f;
    clip_polygon(poly, axis, box.hi[a]);
    clip_polygon(poly, -axis, -box.lo[a]);
  }
}

AABB clipped_triangle_bounds(const Triangle& tri, const AABB& box) {
  const AABB tb = tri.bounds();
  if (!tb.overlaps(box)) return AABB{};
  // Fully inside: no clipping needed.
  if (box.contains(tb.lo) && box.contains(tb.hi)) return tb;
  ClipPolygon poly;
  poly.v[0] = tri.v0;
  poly.v[1] = tri.v1;
  poly.v[2] = tri.v2;
  poly.n = 3;
  clip_polygon_to_box(poly, box);
  AABB out;
  for (int i = 0; i < poly.n; ++i) out.extend(poly.v[i]);
  // Clipped points are computed with rounding; keep the result inside the box.
  return AABB::intersection(out, box);
}

bool triangle_overlaps_box(const Triangle& tri, const AABB& box) {
  return !clipped_triangle_bounds(tri, box).empty();
}

AABB inflate_for_insertion(const AABB& box) {
  const vec3 ext = box.extent();
  const float scale =
      std::max({ext.x, ext.y, ext.z, std::fabs(box.lo.x), std::fabs(box.lo.y), std::fabs(box.lo.z),
                std::fabs(box.hi.x), std::fabs(box.hi.y), std::fabs(box.hi.z)});
  const vec3 margin(scale * 0x1p-18f);
  return {box.lo - margin, box.hi + margin};
}

}  // namespace ab
