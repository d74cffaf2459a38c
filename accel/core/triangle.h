// The one ray/triangle kernel. Every structure calls intersect_triangle with the original ray and
// the triangle's three vertices, so a triangle gives the same t, u, v whichever structure asks.
#pragma once

#include "accel/core/aabb.h"
#include "accel/core/box_test.h"

namespace ab {

/// Three vertices of a triangle, in the order of the file (v0, v1, v2).
struct Triangle {
  vec3 v0, v1, v2;

  /// Bounds of the three vertices and of v0 + (v1 - v0) and v0 + (v2 - v0): the box every structure builds
  /// over, which holds the box the kernel's acceptance tests a hit against (kernel_box).
  AABB bounds() const {
    AABB b = vertex_bounds();
    b.extend(v0 + (v1 - v0));
    b.extend(v0 + (v2 - v0));
    return b;
  }
  /// Bounds of the three vertices alone (the polygon clippers' input).
  AABB vertex_bounds() const {
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

/// A candidate intersection produced by the kernel.
struct TriangleHit {
  float t, u, v;
};

/// Scalar lane helpers: absolute value, "no lane true", "both true".
inline float lane_abs(float x) {
  return std::fabs(x);
}
inline bool lane_none(bool m) {
  return !m;
}
inline bool lane_and(bool a, bool b) {
  return a && b;
}

/// Three coordinates of lane type T (float here, four lanes in triangle4.h). The kernel below is written
/// once over T, with glm's dot and cross expanded in glm's order, so the scalar and the four-lane kernels
/// evaluate the same IEEE operations in the same order and give the same bits.
template <class T>
struct Vec3T {
  T x, y, z;
};

template <class T>
inline Vec3T<T> operator-(const Vec3T<T>& a, const Vec3T<T>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class T>
inline T dot(const Vec3T<T>& a, const Vec3T<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
inline Vec3T<T> cross(const Vec3T<T>& a, const Vec3T<T>& b) {
  return {a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y};
}
/// |x| + |y| + |z| over lanes.
template <class T>
inline T l1_norm(const Vec3T<T>& a) {
  return lane_abs(a.x) + lane_abs(a.y) + lane_abs(a.z);
}

/// The kernel's bound on the rounding of its denominator dot(dir, e1 x e2): relative kCoplanarEps of the
/// L1 product of |dir|, |e1|, |e2|. A ray whose |den| does not exceed it counts as lying in the plane.
template <class T>
inline T parallel_bound(const Vec3T<T>& dir, const Vec3T<T>& e1, const Vec3T<T>& e2) {
  return l1_norm(dir) * l1_norm(e1) * l1_norm(e2) * T(kCoplanarEps);
}

/// What the kernel computes from the triangle alone: v0, the edges e1 = v1 - v0 and e2 = v2 - v0 and the
/// normal n = e1 x e2, with the same operations as triangle_kernel (so leaf blocks may store them, made
/// once at build time, and give the same bits).
template <class T>
struct TriangleTerms {
  Vec3T<T> v0, e1, e2, n;
};

/// The terms of triangle (v0, v1, v2).
template <class T>
[[gnu::always_inline]] inline TriangleTerms<T> triangle_terms(const Vec3T<T>& v0, const Vec3T<T>& v1,
                                                              const Vec3T<T>& v2) {
  const Vec3T<T> e1 = v1 - v0;
  const Vec3T<T> e2 = v2 - v0;
  return {v0, e1, e2, cross(e1, e2)};
}

/// The kernel after triangle_terms and the L1 norms of the direction and the edges (l1_dir = l1_norm(dir),
/// made once per ray; l1_e1 = l1_norm(e1), l1_e2 = l1_norm(e2), made once per triangle or here): the
/// operations of triangle_kernel from the denominator on, in the same order.
template <class T>
[[gnu::always_inline]] inline auto triangle_kernel_norms(const Vec3T<T>& org, const Vec3T<T>& dir, T l1_dir,
                                                         T l1_e1, T l1_e2, T tmin, T tmax,
                                                         const TriangleTerms<T>& tri, T& t, T& u, T& v) {
  const T den = dot(dir, tri.n);
  // A ray lying in the triangle's plane has den = 0 only in exact arithmetic; in floats it is rounding
  // noise, and num/den then puts a "hit" anywhere along the ray, outside every box that holds the
  // triangle. So den must exceed a bound on its rounding error (relative kCoplanarEps of the L1 product
  // of |dir|, |e1|, |e2|), or the ray counts as parallel. The same rule for every structure keeps hits
  // identical; such rays graze the plane within about 1e-5 radians (Embree's differ: verify calls them
  // graze cases). Also rejects NaN. (parallel_bound's product, left to right.)
  auto ok = lane_abs(den) > l1_dir * l1_e1 * l1_e2 * T(kCoplanarEps);
  if (lane_none(ok)) return ok;
  const T inv = T(1.0f) / den;
  const Vec3T<T> to_origin = org - tri.v0;
  const Vec3T<T> c = cross(dir, to_origin);
  u = dot(tri.e2, c) * inv;
  ok = lane_and(ok, u >= T(0.0f));
  if (lane_none(ok)) return ok;
  v = -dot(tri.e1, c) * inv;
  ok = lane_and(ok, lane_and(v >= T(0.0f), u + v <= T(1.0f)));
  if (lane_none(ok)) return ok;
  t = dot(tri.v0 - org, tri.n) * inv;
  return lane_and(ok, lane_and(t >= tmin, t <= tmax));
}

/// The kernel after triangle_terms, with l1_dir = l1_norm(dir) (made once per ray).
template <class T>
[[gnu::always_inline]] inline auto triangle_kernel_terms(const Vec3T<T>& org, const Vec3T<T>& dir, T l1_dir,
                                                         T tmin, T tmax, const TriangleTerms<T>& tri, T& t,
                                                         T& u, T& v) {
  return triangle_kernel_norms(org, dir, l1_dir, l1_norm(tri.e1), l1_norm(tri.e2), tmin, tmax, tri, t, u, v);
}

/// Moller and Trumbore 1997, "Fast, minimum storage ray-triangle intersection", written with the
/// geometric normal n = e1 x e2 (as Embree does) so that a zero-area triangle, whose n is exactly the
/// zero vector, has a zero denominator and never hits; nor does a ray lying in the triangle's plane.
/// Single precision, no fused operations (the build uses -ffp-contract=off), so results are the same bits
/// wherever it is inlined and for every lane type. Returns the lanes where tmin <= t <= tmax and the point
/// lies inside or on the triangle (t, u, v are set where it is true); u and v are the weights of v1 and v2.
template <class T>
[[gnu::always_inline]] inline auto triangle_kernel(const Vec3T<T>& org, const Vec3T<T>& dir, T tmin, T tmax,
                                                   const Vec3T<T>& v0, const Vec3T<T>& v1, const Vec3T<T>& v2,
                                                   T& t, T& u, T& v) {
  return triangle_kernel_terms(org, dir, l1_norm(dir), tmin, tmax, triangle_terms(v0, v1, v2), t, u, v);
}

/// A glm vector as kernel coordinates.
inline Vec3T<float> to_lanes(const vec3& a) {
  return {a.x, a.y, a.z};
}

/// True when the kernel treats the ray as lying in the triangle's plane (it never reports a hit then).
inline bool kernel_calls_parallel(const Ray& ray, const Triangle& tri) {
  const Vec3T<float> e1 = to_lanes(tri.v1) - to_lanes(tri.v0), e2 = to_lanes(tri.v2) - to_lanes(tri.v0);
  const Vec3T<float> dir = to_lanes(ray.dir);
  return !(lane_abs(dot(dir, cross(e1, e2))) > parallel_bound(dir, e1, e2));
}

/// The box the kernel's acceptance tests a hit against: v0, v0 + e1 and v0 + e2 with the edges as the
/// kernel computes them (triangle_terms), so a block of stored terms makes the same box. The sums may lie
/// outside the vertices' box by rounding; Triangle::bounds() holds them.
inline AABB kernel_box(const Vec3T<float>& v0, const Vec3T<float>& e1, const Vec3T<float>& e2) {
  AABB b;
  b.extend(vec3(v0.x, v0.y, v0.z));
  b.extend(vec3(v0.x + e1.x, v0.y + e1.y, v0.z + e1.z));
  b.extend(vec3(v0.x + e2.x, v0.y + e2.y, v0.z + e2.z));
  return b;
}

/// The acceptance of a kernel hit at t: t must lie in the ray's crossing of the triangle's kernel_box as the
/// box walks compute it (within_box_crossing). The kernel's rounding can put a hit a little outside the
/// triangle, and so outside its box: a ray starting on the surface (t near 0, where the walks' relative
/// widening is nothing) or leaving it past a vertex. Such a hit was found by brute but not by a structure
/// that pruned the box; with this rule every structure and brute accept the same hits.
/// r is RayBoxData(ray), made once per ray by the caller.
inline bool kernel_hit_in_box(const Ray& ray, const RayBoxData& r, const TriangleTerms<float>& terms,
                              float t) {
  return within_box_crossing(ray, r, kernel_box(terms.v0, terms.e1, terms.e2), t);
}
/// kernel_hit_in_box of triangle tri, its terms made again (the same operations, so the same box). Kept out
/// of line, from the triangle rather than the kernel's terms: it runs only on a kernel hit (about one a
/// ray), and inlined on the terms it kept them live across the kernel, which then spilled them on its
/// common path, the miss (the grid's closest-hit walk 105.7M -> 124.2M instructions; 106.1M now).
[[gnu::noinline]] inline bool kernel_hit_in_box(const Ray& ray, const Triangle& tri, float t) {
  return kernel_hit_in_box(ray, RayBoxData(ray),
                           triangle_terms(to_lanes(tri.v0), to_lanes(tri.v1), to_lanes(tri.v2)), t);
}

/// A triangle as the kernel sees it, made once: its terms (triangle_terms) and the L1 norms of its edges,
/// the same operations as the kernel makes at run time, so the same bits (as Embree's Triangle4 leaves
/// store v0, the edges and the normal), and its id. A miss, the kernel's common case, then costs the
/// denominator's dot product and the parallel bound's three products instead of about forty operations.
/// One cache line each (aligned in the arrays of LeafRefs): a test reads one line, where a 36-byte
/// Triangle in an array straddles two about half of the time.
struct alignas(64) PreparedTriangle {
  TriangleTerms<float> terms;  ///< v0, e1, e2, n
  float l1_e1, l1_e2;          ///< l1_norm(e1), l1_norm(e2)
  uint32_t id;                 ///< the triangle's id (read only for a hit)
};
static_assert(sizeof(PreparedTriangle) == 64);

/// The prepared form of triangle tri with id `id`.
inline PreparedTriangle prepare_triangle(const Triangle& tri, uint32_t id) {
  const TriangleTerms<float> terms = triangle_terms(to_lanes(tri.v0), to_lanes(tri.v1), to_lanes(tri.v2));
  return {terms, l1_norm(terms.e1), l1_norm(terms.e2), id};
}

/// kernel_hit_in_box of a prepared triangle (its stored terms: the same box). Out of line, as above.
[[gnu::noinline]] inline bool kernel_hit_in_box(const Ray& ray, const PreparedTriangle& tri, float t) {
  return kernel_hit_in_box(ray, RayBoxData(ray), tri.terms, t);
}

/// The kernel with its acceptance on a prepared triangle, l1_dir = l1_norm(ray.dir) made once per ray: the
/// same verdict and t, u, v bits as intersect_triangle on the triangle it was made from.
[[gnu::always_inline]] inline bool intersect_prepared(const Ray& ray, float l1_dir,
                                                      const PreparedTriangle& tri, TriangleHit& out) {
  float t, u, v;
  if (!triangle_kernel_norms<float>(to_lanes(ray.org), to_lanes(ray.dir), l1_dir, tri.l1_e1, tri.l1_e2,
                                    ray.tmin, ray.tmax, tri.terms, t, u, v))
    return false;
  if (!kernel_hit_in_box(ray, tri, t)) return false;
  out = {t, u, v};
  return true;
}

/// The kernel for one triangle, with its acceptance (kernel_hit_in_box). Returns true and fills out on a
/// hit. Always inlined, as intersect_and_update: with the acceptance's call GCC stopped inlining them into
/// the walks' loops.
[[gnu::always_inline]] inline bool intersect_triangle(const Ray& ray, const Triangle& tri, TriangleHit& out) {
  float t, u, v;
  if (!triangle_kernel<float>(to_lanes(ray.org), to_lanes(ray.dir), ray.tmin, ray.tmax, to_lanes(tri.v0),
                              to_lanes(tri.v1), to_lanes(tri.v2), t, u, v))
    return false;
  if (!kernel_hit_in_box(ray, tri, t)) return false;
  out = {t, u, v};
  return true;
}

/// Records the kernel's hit of triangle `prim` of instance `inst` in `best` when the acceptance rule
/// (is_better_hit) prefers it. Returns true when `best` changed.
inline bool accept_hit(const TriangleHit& th, uint32_t prim, uint32_t inst, Hit& best) {
  if (!is_better_hit(th.t, inst, prim, best)) return false;
  best = {th.t, prim, inst, th.u, th.v};
  return true;
}

/// Tests triangle `prim` of instance `inst` and, when it is hit and better than `best` by the
/// one acceptance rule (is_better_hit), records it. Returns true when `best` changed.
[[gnu::always_inline]] inline bool intersect_and_update(const Ray& ray, const Triangle& tri, uint32_t prim,
                                                        uint32_t inst, Hit& best) {
  TriangleHit th;
  return intersect_triangle(ray, tri, th) && accept_hit(th, prim, inst, best);
}

}  // namespace ab
