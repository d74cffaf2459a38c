// Primitives with NaN or infinite coordinates have no place in a subdivision of space: they are kept
// apart (tested for every ray, so their ids and any hit they give are kept) and the tree is built over
// the others. Triangles the kernel can never hit (a normal of exactly zero) are left out.
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/primitives.h"
#include "accel/core/triangle.h"

namespace ab {

/// True when every coordinate of b is finite and b is not empty.
inline bool finite_box(const AABB& b) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(b.lo[a]) || !std::isfinite(b.hi[a])) return false;
  return !b.empty();
}

/// True when the kernel can never hit t: its normal e1 x e2, made with the kernel's own operations
/// (triangle_terms), is exactly zero (a point, two equal vertices, or collinear vertices whose products
/// cancel exactly). The kernel's denominator dot(dir, n) is then 0 (or NaN), never above its bound, so no ray
/// hits it (200k such triangles and collinear ones cost kdtree-sah 15.0 s of build and the bsp 6.2 s; 20k the
/// bsp 2.5 s).
inline bool never_hit(const Triangle& t) {
  const Vec3T<float> n = triangle_terms(to_lanes(t.v0), to_lanes(t.v1), to_lanes(t.v2)).n;
  return n.x == 0.0f && n.y == 0.0f && n.z == 0.0f;
}

/// never_hit for primitive i of prims: its triangle's, false for other primitives.
template <class P>
bool never_hit(const P& prims, size_t i) {
  if constexpr (std::is_same_v<P, TrianglePrims>)
    return never_hit(prims.triangle(i));
  else
    return false;
}

/// The primitives of prims the kernel can never hit (never_hit), for the build statistics.
template <class P>
size_t count_never_hit(const P& prims) {
  size_t n = 0;
  for (size_t i = 0; i < prims.size(); ++i) n += never_hit(prims, i);
  return n;
}

/// Splits the primitives of `prims` into those with finite bounds (returned; their union goes into `box`)
/// and the rest (`unbounded`: tested for every ray, so their ids and any hit are kept); those the kernel can
/// never hit (never_hit) are in neither.
template <class P>
std::vector<uint32_t> partition_finite(const P& prims, std::vector<uint32_t>& unbounded, AABB& box) {
  std::vector<uint32_t> ids;
  unbounded.clear();
  box = AABB{};
  for (size_t i = 0; i < prims.size(); ++i) {
    if (never_hit(prims, i)) continue;
    const AABB b = prims.bounds(i);
    if (finite_box(b)) {
      ids.push_back(uint32_t(i));
      box.extend(b);
    } else {
      unbounded.push_back(uint32_t(i));
    }
  }
  return ids;
}

}  // namespace ab
