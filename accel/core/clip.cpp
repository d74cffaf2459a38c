#include "accel/core/clip.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

namespace ab {

namespace {

/// One Sutherland and Hodgman (1974) step: the part of in with dot(normal, p) <= offset into out. Returns
/// false, out untouched, when every point of in already lies on that side: the step would return in
/// unchanged, point for point, so the caller keeps in (no copy). The distances are computed once per point.
bool clip_step(const ClipPolygon& in, const vec3& normal, float offset, ClipPolygon& out) {
  std::array<float, std::tuple_size_v<decltype(in.v)>> d;
  bool inside = true, outside = true;
  for (int i = 0; i < in.n; ++i) {
    d[i] = glm::dot(normal, in.v[i]) - offset;
    inside = inside && d[i] <= 0.0f;
    outside = outside && d[i] > 0.0f;
  }
  if (inside) return false;
  out.n = 0;
  if (outside) return true;
  const int cap = static_cast<int>(out.v.size());
  for (int i = 0; i < in.n; ++i) {
    const int j = i + 1 == in.n ? 0 : i + 1;
    const float da = d[i], db = d[j];
    if (da <= 0.0f && out.n < cap) out.v[out.n++] = in.v[i];
    if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {
      const float s = da / (da - db);
      if (out.n < cap) out.v[out.n++] = in.v[i] + s * (in.v[j] - in.v[i]);
    }
  }
  return true;
}

/// Copies the n points of from into to.
void assign(ClipPolygon& to, const ClipPolygon& from) {
  std::copy(from.v.begin(), from.v.begin() + from.n, to.v.begin());
  to.n = from.n;
}

/// Clips poly by the box's six axis planes, ping-ponging between poly and spare: returns the one holding
/// the result. A plane the polygon lies inside is skipped (clip_step returns false).
const ClipPolygon& clip_to_box(ClipPolygon& poly, ClipPolygon& spare, const AABB& box) {
  ClipPolygon* cur = &poly;
  ClipPolygon* other = &spare;
  for (int a = 0; a < 3 && cur->n > 0; ++a) {
    vec3 axis(0.0f);
    axis[a] = 1.0f;
    if (clip_step(*cur, axis, box.hi[a], *other)) std::swap(cur, other);
    if (cur->n > 0 && clip_step(*cur, -axis, -box.lo[a], *other)) std::swap(cur, other);
  }
  return *cur;
}

}  // namespace

void clip_polygon(ClipPolygon& poly, const vec3& normal, float offset) {
  ClipPolygon out;
  if (clip_step(poly, normal, offset, out)) assign(poly, out);
}

void clip_polygon_to_box(ClipPolygon& poly, const AABB& box) {
  ClipPolygon spare;
  const ClipPolygon& out = clip_to_box(poly, spare, box);
  if (&out != &poly) assign(poly, out);
}

AABB clipped_triangle_bounds(const Triangle& tri, const AABB& box) {
  const AABB tb = tri.vertex_bounds();
  if (!tb.overlaps(box)) return AABB{};
  // Fully inside: no clipping needed.
  if (box.contains(tb.lo) && box.contains(tb.hi)) return tb;
  ClipPolygon poly, spare;
  poly.v[0] = tri.v0;
  poly.v[1] = tri.v1;
  poly.v[2] = tri.v2;
  poly.n = 3;
  const ClipPolygon& clipped = clip_to_box(poly, spare, box);
  AABB out;
  for (int i = 0; i < clipped.n; ++i) out.extend(clipped.v[i]);
  // Clipped points are computed with rounding; keep the result inside the box.
  return AABB::intersection(out, box);
}

bool triangle_overlaps_box(const Triangle& tri, const AABB& box) {
  return !clipped_triangle_bounds(tri, box).empty();
}

}  // namespace ab
