// Four triangles tested at once by the one kernel (triangle.h's triangle_kernel_terms instantiated on four
// SSE lanes), as Embree's Triangle4 leaves do. Every lane performs the scalar kernel's IEEE operations in the
// same order, so each lane's t, u, v and verdict are the bits intersect_triangle gives for that triangle.
#pragma once

#include <immintrin.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>

#include "accel/core/triangle.h"

namespace ab {

/// Four floats in one SSE register, with the arithmetic the kernel uses (SSE2 only: comparisons are ordered,
/// false on NaN, like the scalar ones).
struct Lanes4 {
  __m128 v;
  Lanes4() = default;
  explicit Lanes4(__m128 x) : v(x) {}
  explicit Lanes4(float x) : v(_mm_set1_ps(x)) {}
};
/// A per-lane truth value (all bits set where true).
struct Mask4 {
  __m128 m;
};
inline Lanes4 operator+(Lanes4 a, Lanes4 b) {
  return Lanes4(_mm_add_ps(a.v, b.v));
}
inline Lanes4 operator-(Lanes4 a, Lanes4 b) {
  return Lanes4(_mm_sub_ps(a.v, b.v));
}
inline Lanes4 operator*(Lanes4 a, Lanes4 b) {
  return Lanes4(_mm_mul_ps(a.v, b.v));
}
inline Lanes4 operator/(Lanes4 a, Lanes4 b) {
  return Lanes4(_mm_div_ps(a.v, b.v));
}
inline Lanes4 operator-(Lanes4 a) {
  return Lanes4(_mm_xor_ps(a.v, _mm_set1_ps(-0.0f)));
}
inline Mask4 operator>(Lanes4 a, Lanes4 b) {
  return {_mm_cmpgt_ps(a.v, b.v)};
}
inline Mask4 operator>=(Lanes4 a, Lanes4 b) {
  return {_mm_cmpge_ps(a.v, b.v)};
}
inline Mask4 operator<=(Lanes4 a, Lanes4 b) {
  return {_mm_cmple_ps(a.v, b.v)};
}
inline Lanes4 lane_abs(Lanes4 a) {
  return Lanes4(_mm_andnot_ps(_mm_set1_ps(-0.0f), a.v));
}
inline bool lane_none(Mask4 m) {
  return _mm_movemask_ps(m.m) == 0;
}
inline Mask4 lane_and(Mask4 a, Mask4 b) {
  return {_mm_and_ps(a.m, b.m)};
}

/// Four triangles in structure-of-arrays form, as the kernel's triangle terms (triangle_terms: v0, e1, e2,
/// n; row[term][axis][lane]) computed once when packing, as Embree's Triangle4 stores v0, e1, e2 and Ng: the
/// same IEEE operations as the kernel makes at run time, so the same bits. Unused lanes hold a zero-area
/// triangle (all terms zero), which the kernel never reports. 192 bytes: three cache lines.
struct alignas(64) Triangle4 {
  float row[4][3][4];

  /// Packs up to four triangles (the rest of the lanes are left zero-area).
  static Triangle4 pack(std::span<const Triangle> tris) {
    Triangle4 out{};
    for (size_t k = 0; k < tris.size() && k < 4; ++k) out.set_lane(int(k), tris[k]);
    return out;
  }
  /// Writes the terms of triangle tri into lane k (the other lanes are unchanged).
  void set_lane(int k, const Triangle& tri) {
    const TriangleTerms<float> terms = triangle_terms(to_lanes(tri.v0), to_lanes(tri.v1), to_lanes(tri.v2));
    const Vec3T<float>* rows[4] = {&terms.v0, &terms.e1, &terms.e2, &terms.n};
    for (int r = 0; r < 4; ++r) {
      row[r][0][k] = rows[r]->x;
      row[r][1][k] = rows[r]->y;
      row[r][2][k] = rows[r]->z;
    }
  }
  /// One term of all four lanes as kernel coordinates.
  [[gnu::always_inline]] Vec3T<Lanes4> term(int r) const {
    return {Lanes4(_mm_load_ps(row[r][0])), Lanes4(_mm_load_ps(row[r][1])), Lanes4(_mm_load_ps(row[r][2]))};
  }
  /// The terms of lane k.
  TriangleTerms<float> lane_terms(int k) const {
    TriangleTerms<float> out;
    Vec3T<float>* rows[4] = {&out.v0, &out.e1, &out.e2, &out.n};
    for (int r = 0; r < 4; ++r) *rows[r] = {row[r][0][k], row[r][1][k], row[r][2][k]};
    return out;
  }
  /// The four triangles' terms as the kernel takes them.
  [[gnu::always_inline]] TriangleTerms<Lanes4> terms() const { return {term(0), term(1), term(2), term(3)}; }
};
static_assert(sizeof(Triangle4) == 192);

/// A ray broadcast to four lanes, with the L1 norm of its direction (made once per ray, as the kernel makes
/// it), and the ray itself and its box data for the acceptance of a hit (kernel_hit_in_box; the ray and the
/// box data, RayBoxData(ray), must outlive this: the 8-wide walk passes its box test's, so the reciprocals
/// are divided once per ray). A closest-hit walk lowers tmax to the best hit's t (set_tmax): the kernel's t,
/// u and v do not depend on tmax, and a hit beyond the best one, which the acceptance rule refuses anyway,
/// then skips the acceptance's box check.
struct Ray4 {
  /// Ray r in four lanes; box_data is RayBoxData(r), kept by pointer.
  Ray4(const Ray& r, const RayBoxData& box_data)
      : org{Lanes4(r.org.x), Lanes4(r.org.y), Lanes4(r.org.z)},
        dir{Lanes4(r.dir.x), Lanes4(r.dir.y), Lanes4(r.dir.z)},
        l1_dir(l1_norm(to_lanes(r.dir))),
        tmin(r.tmin),
        tmax(r.tmax),
        ray(&r),
        box(&box_data) {}
  /// Lanes' tmax: min(the ray's tmax, t), t the best hit so far.
  void set_tmax(float t) { tmax = Lanes4(std::min(ray->tmax, t)); }
  Vec3T<Lanes4> org, dir;
  Lanes4 l1_dir, tmin, tmax;
  const Ray* ray;
  const RayBoxData* box;
};

/// The kernel on four triangles: returns the mask of lanes hit (bit k for lane k) and their t, u, v.
[[gnu::always_inline]] inline unsigned intersect_triangle4(const Ray4& ray, const Triangle4& tris, float* t,
                                                           float* u, float* v) {
  Lanes4 lt, lu, lv;
  const Mask4 hit = triangle_kernel_terms<Lanes4>(ray.org, ray.dir, ray.l1_dir, ray.tmin, ray.tmax,
                                                  tris.terms(), lt, lu, lv);
  unsigned mask = unsigned(_mm_movemask_ps(hit.m));
  if (mask) {
    _mm_storeu_ps(t, lt.v);
    _mm_storeu_ps(u, lu.v);
    _mm_storeu_ps(v, lv.v);
    for (unsigned rest = mask; rest; rest &= rest - 1) {  // the acceptance, lane by lane (hits are rare)
      const int k = std::countr_zero(rest);
      if (!kernel_hit_in_box(*ray.ray, *ray.box, tris.lane_terms(k), t[k])) mask &= ~(1u << k);
    }
  }
  return mask;
}

}  // namespace ab
