// The one ray/triangle kernel. Every structure calls intersect_triangle with the original ray and
// the triangle's three vertices, so a triangle gives the same t, u, v whichever structure asks.
#pragma once

#include "accel/geometry.h"

namespace ab {

/// Three vertices of a triangle, in the order of the file (v0, v1, v2).
struct Triangle {
  vec3 v0, v1, v2;

  /// Bounds of the three vertices.
  AABB bounds() const {
    AABB b;
    b.extend(v0);
    b.extend(v1);
    b.extend(v2);
    return b;
  }
  /// Centroid of the vertices.
  vec3 centroid() const { return (v0 + v1 + v2) * (1.0f / 3.0f); }
};
static_assert(sizeof(Triangle) == 36);

/// Relative bound on the rounding of the kernel's denominator (see intersect_triangle).
inline constexpr float kCoplanarEps = 0x1p-18f;

/// |x| + |y| + |z|.
inline float l1_norm(const vec3& v) { return std::fabs(v.x) + std::fabs(v.y) + std::fabs(v.z); }

/// A candidate intersection produced by the kernel.
struct TriangleHit {
  float t, u, v;
};

/// Moller and Trumbore 1997, "Fast, minimum storage ray-triangle intersection", written with the
/// geometric normal n = e1 x e2 (as Embree does) so that a zero-area triangle, whose n is exactly the
/// zero vector, has a zero denominator and never hits; nor does a ray lying in the triangle's plane. Single precision, no fused operations
/// (the build uses -ffp-contract=off), so results are the same bits wherever it is inlined.
/// Returns true and fills out when tmin <= t <= tmax and the point lies inside or on the triangle;
/// u and v are the weights of v1 and v2.
inline bool intersect_triangle(const Ray& ray, const Triangle& tri, TriangleHit& out) {
  const vec3 e1 = tri.v1 - tri.v0;
  const vec3 e2 = tri.v2 - tri.v0;
  const vec3 n = glm::cross(e1, e2);
  const float den = glm::dot(ray.dir, n);
  // A ray lying in the triangle's plane has den = 0 only in exact arithmetic; in floats it is rounding
  // noise, and num/den then puts a "hit" anywhere along the ray, outside every box that holds the
  // triangle. So den must exceed a bound on its rounding error (relative kCoplanarEps of the L1 product
  // of |dir|, |e1|, |e2|), or the ray counts as parallel. The same rule for every structure keeps hits
  // identical; such rays graze the plane within about 1e-5 radians (Embree's differ: verify calls them
  // graze cases). Also rejects NaN.
  const float scale = l1_norm(ray.dir) * l1_norm(e1) * l1_norm(e2);
  if (!(std::fabs(den) > scale * kCoplanarEps)) return false;
  const float inv = 1.0f / den;
  const vec3 to_origin = ray.org - tri.v0;
  const vec3 c = glm::cross(ray.dir, to_origin);
  const float u = glm::dot(e2, c) * inv;
  if (!(u >= 0.0f)) return false;
  const float v = -glm::dot(e1, c) * inv;
  if (!(v >= 0.0f) || !(u + v <= 1.0f)) return false;
  const float t = glm::dot(tri.v0 - ray.org, n) * inv;
  if (!(t >= ray.tmin) || !(t <= ray.tmax)) return false;
  out = {t, u, v};
  return true;
}

/// Tests triangle `prim` of instance `inst` and, when it is hit and better than `best` by the
/// one acceptance rule (is_better_hit), records it. Returns true when `best` changed.
inline bool intersect_and_update(const Ray& ray, const Triangle& tri, uint32_t prim, uint32_t inst, Hit& best) {
  TriangleHit th;
  if (!intersect_triangle(ray, tri, th)) return false;
  if (!is_better_hit(th.t, inst, prim, best)) return false;
  best = {th.t, prim, inst, th.u, th.v};
  return true;
}

}  // namespace ab
