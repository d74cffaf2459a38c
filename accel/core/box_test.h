// The robust ray/box slab test shared by every structure (Ize 2013, "Robust BVH ray traversal").
#pragma once

#include <cmath>

#include "accel/core/aabb.h"
#include "accel/core/ray.h"

namespace ab {

/// Per-ray data precomputed once for box tests. A zero direction component gives an infinite
/// reciprocal; the slab test below is written so that the NaN of 0 * inf never narrows the interval.
struct RayBoxData {
  vec3 org;
  vec3 inv_dir;
  int neg[3];  ///< 1 where the direction component's sign bit is set (also for -0)

  explicit RayBoxData(const Ray& r) : org(r.org), inv_dir(1.0f / r.dir.x, 1.0f / r.dir.y, 1.0f / r.dir.z) {
    neg[0] = std::signbit(r.dir.x);
    neg[1] = std::signbit(r.dir.y);
    neg[2] = std::signbit(r.dir.z);
  }
};

/// Relative widening of both slab distances. Ize 2013 ("Robust BVH ray traversal") shows that
/// far *= 1 + 2 gamma(3) suffices for the box test itself; we widen both ends, by |t| so that boxes
/// behind the origin widen too, and by more than that bound so that a triangle whose kernel t lies a
/// few ulps outside its box's computed interval (flat geometry on a box face) is never culled or
/// passed over in a tie.
inline constexpr float kBoxEps = 0x1p-16f;

/// Widens a near distance towards -inf (conservative).
inline float widen_near(float t) {
  return t * (t > 0.0f ? 1.0f - kBoxEps : 1.0f + kBoxEps);
}
/// Widens a far distance towards +inf (conservative).
inline float widen_far(float t) {
  return t * (t > 0.0f ? 1.0f + kBoxEps : 1.0f - kBoxEps);
}

/// Clips [t0, t1] against box b. Returns false when the ray misses it within that interval.
/// On return [t0, t1] is the (conservatively widened) overlap. The near plane per axis is chosen by
/// the direction's sign, and comparisons keep the current bound when a slab distance is NaN
/// (origin exactly on a slab plane of an axis the ray is parallel to), so the result is never NaN.
inline bool slab_test(const AABB& b, const RayBoxData& r, float& t0, float& t1) {
  for (int a = 0; a < 3; ++a) {
    const float near_plane = r.neg[a] ? b.hi[a] : b.lo[a];
    const float far_plane = r.neg[a] ? b.lo[a] : b.hi[a];
    const float tn = widen_near((near_plane - r.org[a]) * r.inv_dir[a]);
    const float tf = widen_far((far_plane - r.org[a]) * r.inv_dir[a]);
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  return t0 <= t1;
}

/// True when t lies in the ray's crossing of box b as every box walk computes it: the general path
/// (slab_test: the binary walk's arithmetic, and the 8-wide walk's for tmin < 0; widening each axis's
/// distance or their reduction is the same, widen_near and widen_far being monotone) and, for tmin >= 0,
/// the 8-wide walk's folded path (Bvh8RayTest: the widening folded into the reciprocals). Both are monotone
/// in the box (a larger box gives each bound the same or a wider value, bit for bit), so a t that passes for
/// a triangle's box passes for every box that holds it: the kernel's acceptance (intersect_triangle) asks
/// this of the triangle's own box, and every BVH then enters each node on the way to that triangle. r is
/// RayBoxData(ray), which a caller testing many hits of one ray makes once.
inline bool within_box_crossing(const Ray& ray, const RayBoxData& r, const AABB& b, float t) {
  float t0 = -kInf, t1 = kInf;
  if (!slab_test(b, r, t0, t1) || !(t0 <= t && t <= t1)) return false;
  if (ray.tmin < 0.0f) return true;
  float fn = -kInf, ff = kInf;
  for (int a = 0; a < 3; ++a) {
    const float dn = (r.neg[a] ? b.hi[a] : b.lo[a]) - r.org[a];
    const float df = (r.neg[a] ? b.lo[a] : b.hi[a]) - r.org[a];
    const float n = dn * (r.inv_dir[a] * (1.0f - kBoxEps)), f = df * (r.inv_dir[a] * (1.0f + kBoxEps));
    fn = n > fn ? n : fn;  // a NaN distance keeps the bound, as in every walk
    ff = f < ff ? f : ff;
  }
  return fn <= t && t <= ff;
}

/// within_box_crossing with the ray's box data made here (the same reciprocals as the walks').
inline bool within_box_crossing(const Ray& ray, const AABB& b, float t) {
  return within_box_crossing(ray, RayBoxData(ray), b, t);
}

}  // namespace ab
