// Candidate split planes of the BSP tree and their surface-area cost, after Ize, Wald and Parker 2008
// ("Ray tracing with the BSP tree") and Kammaje and Mora 2007 ("A study of restricted BSP trees for ray
// tracing"): planes from a fixed set of 13 directions (the 3 axes, the 6 face diagonals and the 4 cube
// diagonals), positioned at bin boundaries of the primitives' extents along each direction, plus the
// supporting planes of a few of the node's own triangles (the autopartition). A plane is scored by the
// SAH over the node's convex cell (cell.h). cut_box gives the bounding box of a box cut by a plane.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <limits>
#include <span>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/instances.h"
#include "accel/core/motion_prims.h"
#include "accel/core/primitives.h"

namespace ab {

/// |v|: glm::length(v) (the same bits) where its squares neither overflow nor lose bits to underflow, and
/// |v| computed on v scaled by its largest component's magnitude beyond that. The cell's areas are lengths
/// of cross products, squared lengths in the squares: glm::length alone overflowed from coordinates of
/// about 1e10 and underflowed below 1e-10 (a soup at 1e12 and 1e-12: 148 and 96 triangle tests per ray
/// against 7.1; at 1e18 a single leaf).
inline float robust_length(const vec3& v) {
  const float l = glm::length(v);
  if (l < 0x1p63f && l > 0x1p-63f) return l;
  const float m = std::max({std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
  if (!(m > 0.0f && m < std::numeric_limits<float>::infinity())) return l;  // zero, infinite or NaN
  return m * glm::length(v / m);
}

/// A plane dot(n, x) = d with a unit normal; "below" is dot(n, x) < d.
struct BspPlane {
  vec3 n{1.0f, 0.0f, 0.0f};  ///< unit normal
  float d = 0.0f;            ///< offset along n

  /// Signed distance of p (positive above).
  float distance(const vec3& p) const { return glm::dot(n, p) - d; }
};
static_assert(sizeof(BspPlane) == 16);

/// True when the plane's normal is not one of the three axes.
inline bool is_oblique(const BspPlane& p) {
  return !(p.n.x == 1.0f || p.n.y == 1.0f || p.n.z == 1.0f);
}

/// The axis of a plane whose normal is exactly an axis (0, 1, 2), else -1. (A normal whose other components
/// are tiny but not zero can still round to a component of exactly 1, as is_oblique sees it.)
inline int exact_axis(const BspPlane& p) {
  for (int a = 0; a < 3; ++a)
    if (p.n[a] == 1.0f && p.n[(a + 1) % 3] == 0.0f && p.n[(a + 2) % 3] == 0.0f) return a;
  return -1;
}

/// The 13 fixed directions (unit length).
inline const std::array<vec3, 13>& bsp_directions() {
  static const std::array<vec3, 13> dirs = [] {
    const std::array<vec3, 13> raw{vec3(1, 0, 0),  vec3(0, 1, 0), vec3(0, 0, 1),  vec3(1, 1, 0),
                                   vec3(1, -1, 0), vec3(1, 0, 1), vec3(1, 0, -1), vec3(0, 1, 1),
                                   vec3(0, 1, -1), vec3(1, 1, 1), vec3(1, 1, -1), vec3(1, -1, 1),
                                   vec3(-1, 1, 1)};
    std::array<vec3, 13> out;
    for (size_t i = 0; i < raw.size(); ++i) out[i] = glm::normalize(raw[i]);
    return out;
  }();
  return dirs;
}

/// The indices into bsp_directions() of a restricted BSP's k directions (Kammaje and Mora 2007 compare
/// restricted BSP trees by their number of fixed directions): 3 the axes (a k-d tree's planes), 7 the axes
/// and the 4 cube diagonals, 9 the axes and the 6 face diagonals, 13 all of them (any other k: 13).
inline std::span<const size_t> bsp_direction_set(int k) {
  static constexpr size_t all[13] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  static constexpr size_t cube[7] = {0, 1, 2, 9, 10, 11, 12};
  if (k == 3) return {all, 3};
  if (k == 7) return {cube, 7};
  if (k == 9) return {all, 9};
  return {all, 13};
}

/// Most support points a primitive can have in a cell (a triangle clipped by a box).
inline constexpr int kMaxSupportPoints = 32;

/// Triangle t in a frame whose origin is at `origin` (BspTree's local frame far from the origin).
inline Triangle translated(const Triangle& t, const vec3& origin) {
  return {t.v0 - origin, t.v1 - origin, t.v2 - origin};
}

/// The points whose convex hull holds the part of triangle i inside box: the triangle clipped to the box
/// (Sutherland-Hodgman, clip.h). Zero points when it misses the box. Box and points are in the frame whose
/// origin is at `origin` (0: the world's, the same bits).
inline int support_points(const TrianglePrims& p, size_t i, const AABB& box, vec3* out, const vec3& origin) {
  const Triangle t = translated(p.triangle(i), origin);
  ClipPolygon poly;
  poly.v[0] = t.v0;
  poly.v[1] = t.v1;
  poly.v[2] = t.v2;
  poly.n = 3;
  const AABB tb = t.bounds();
  if (!tb.overlaps(box)) return 0;
  if (!(box.contains(tb.lo) && box.contains(tb.hi))) clip_polygon_to_box(poly, box);
  for (int k = 0; k < poly.n; ++k) out[k] = poly.v[k];
  return poly.n;
}
/// The support points in box of a primitive known by its box only (an instance's world box, a moving
/// triangle's swept box): the corners of that box clipped to box.
template <class P>
requires std::same_as<P, InstancePrims> || std::same_as<P, MotionTrianglePrims>
inline int support_points(const P& p, size_t i, const AABB& box, vec3* out, const vec3& origin) {
  const AABB world = p.bounds(i);
  const AABB b = AABB::intersection({world.lo - origin, world.hi - origin}, box);
  if (b.empty()) return 0;
  for (int c = 0; c < 8; ++c)
    out[c] = vec3((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z);
  return 8;
}

/// The supporting plane of triangle i (false for a degenerate triangle), in the frame whose origin is at
/// `origin`.
inline bool supporting_plane(const TrianglePrims& p, size_t i, BspPlane& plane, const vec3& origin) {
  const Triangle t = translated(p.triangle(i), origin);
  const vec3 n = glm::cross(t.v1 - t.v0, t.v2 - t.v0);
  const float len = robust_length(n);
  if (!(len > 0.0f) || !std::isfinite(len)) return false;
  plane.n = n / len;
  plane.d = glm::dot(plane.n, t.v0);
  return std::isfinite(plane.d);
}
/// Instances and moving triangles offer no supporting plane (their boxes are classified by corners only).
template <class P>
requires std::same_as<P, InstancePrims> || std::same_as<P, MotionTrianglePrims>
inline bool supporting_plane(const P&, size_t, BspPlane&, const vec3&) {
  return false;
}

/// Bounding box of the part of box b with dot(n, x) <= d (below) or >= d (above): the corners on that side
/// and the points where the plane cuts the twelve edges. Empty when that part is empty.
inline AABB cut_box(const AABB& b, const BspPlane& plane, bool below) {
  AABB out;
  if (b.empty()) return out;
  std::array<vec3, 8> c;
  std::array<float, 8> s;
  for (int k = 0; k < 8; ++k) {
    c[k] = vec3((k & 1) ? b.hi.x : b.lo.x, (k & 2) ? b.hi.y : b.lo.y, (k & 4) ? b.hi.z : b.lo.z);
    s[k] = below ? plane.distance(c[k]) : -plane.distance(c[k]);
    if (s[k] <= 0.0f) out.extend(c[k]);
  }
  for (int k = 0; k < 8; ++k)
    for (int bit = 1; bit < 8; bit <<= 1) {
      const int j = k | bit;
      if (j == k || !((s[k] < 0.0f && s[j] > 0.0f) || (s[k] > 0.0f && s[j] < 0.0f))) continue;
      out.extend(c[k] + (s[k] / (s[k] - s[j])) * (c[j] - c[k]));
    }
  return AABB::intersection(out, b);
}

}  // namespace ab
