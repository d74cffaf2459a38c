// The octree's insertion of one triangle into the eight children of a node in one pass: the triangle is
// clipped once to the box around the children's grown boxes, and the polygon split by the three mid-planes,
// each widened to a band of the children's largest insertion margin (Sutherland and Hodgman 1974 against
// axis planes only): 6 + 14 clips instead of 8 x 6 for the exact test against each grown child box, and none
// for a triangle whose bounds reach one child only. Each octant's region (that box, cut by the bands) holds
// its grown child box, so a triangle goes into every child the exact test would put it in, and at most into
// a few more within the margins.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "accel/core/aabb.h"
#include "accel/core/triangle.h"

namespace ab {

/// A convex polygon cut by axis planes (a triangle cut by 9 planes has at most 12 vertices).
struct OctPolygon {
  static constexpr int kCapacity = 24;  ///< room for the extra crossings rounding can give
  std::array<vec3, kCapacity> v;        ///< vertices
  int n = 0;                            ///< vertex count
  bool overflow = false;                ///< a clip ran out of room (the caller falls back to the exact test)
};

/// The part of `in` with sign * (p[axis] - plane) <= 0 into out.
inline void clip_axis(const OctPolygon& in, int axis, float plane, float sign, OctPolygon& out) {
  out.n = 0;
  out.overflow = in.overflow;
  for (int i = 0; i < in.n; ++i) {
    const vec3& a = in.v[i];
    const vec3& b = in.v[i + 1 == in.n ? 0 : i + 1];
    const float da = sign * (a[axis] - plane), db = sign * (b[axis] - plane);
    const bool cross = (da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f);
    if (out.n + int(da <= 0.0f) + int(cross) > OctPolygon::kCapacity) {
      out.overflow = true;
      return;
    }
    if (da <= 0.0f) out.v[out.n++] = a;
    if (cross) out.v[out.n++] = a + (da / (da - db)) * (b - a);
  }
}

/// The octants of a node: the box around its grown child boxes, its mid-planes and the band half-width.
struct OctantFrame {
  AABB outer;         ///< union of the grown child boxes
  vec3 mid{0.0f};     ///< the mid-planes (octant_box's)
  float band = 0.0f;  ///< the largest growth of a child box (its insertion margin)

  /// The frame of child boxes child[k] and their grown boxes grown[k] (InsertionMargin::inflate).
  OctantFrame(const AABB& box, const std::array<AABB, 8>& child, const std::array<AABB, 8>& grown) {
    for (int k = 0; k < 8; ++k) {
      outer.extend(grown[k]);
      for (int a = 0; a < 3; ++a)
        band = std::max({band, grown[k].hi[a] - child[k].hi[a], child[k].lo[a] - grown[k].lo[a]});
    }
    for (int a = 0; a < 3; ++a) mid[a] = 0.5f * (box.lo[a] + box.hi[a]);
  }
};

/// The octant bits of a polygon inside the outer box: split along `axis` and the following ones into the
/// band-widened halves (bits so far in `bits`); -1 when a clip overflowed.
inline int split_octants(const OctPolygon& poly, const OctantFrame& f, int axis, int bits) {
  if (axis == 3) return 1 << bits;
  int out = 0;
  for (int side = 0; side < 2; ++side) {
    OctPolygon half;
    if (side == 0)
      clip_axis(poly, axis, f.mid[axis] + f.band, 1.0f, half);  // p <= mid + band
    else
      clip_axis(poly, axis, f.mid[axis] - f.band, -1.0f, half);  // p >= mid - band
    if (half.overflow) return -1;
    if (half.n == 0) continue;
    const int r = split_octants(half, f, axis + 1, bits | (side << axis));
    if (r < 0) return -1;
    out |= r;
  }
  return out;
}

/// Sets bit k of the result for every octant k whose region the triangle meets; -1 when a clip overflowed.
inline int triangle_octants(const Triangle& t, const OctantFrame& f) {
  const AABB tb = t.bounds();
  if (!tb.overlaps(f.outer)) return 0;
  int lo_side[3], hi_side[3];  // the sides each axis's bounds reach
  for (int a = 0; a < 3; ++a) {
    lo_side[a] = tb.lo[a] <= f.mid[a] + f.band;
    hi_side[a] = tb.hi[a] >= f.mid[a] - f.band;
  }
  const bool inside = f.outer.contains(tb.lo) && f.outer.contains(tb.hi);
  if (inside && lo_side[0] + hi_side[0] == 1 && lo_side[1] + hi_side[1] == 1 && lo_side[2] + hi_side[2] == 1)
    return 1 << (hi_side[0] | (hi_side[1] << 1) | (hi_side[2] << 2));  // within one octant's region
  OctPolygon poly, tmp;
  poly.v[0] = t.v0, poly.v[1] = t.v1, poly.v[2] = t.v2, poly.n = 3;
  for (int a = 0; a < 3 && !inside; ++a) {  // to the outer box, only by the planes that cut
    if (tb.hi[a] > f.outer.hi[a]) clip_axis(poly, a, f.outer.hi[a], 1.0f, tmp), poly = tmp;
    if (tb.lo[a] < f.outer.lo[a]) clip_axis(poly, a, f.outer.lo[a], -1.0f, tmp), poly = tmp;
  }
  if (poly.overflow) return -1;
  if (poly.n == 0) return 0;
  return split_octants(poly, f, 0, 0);
}

}  // namespace ab
