// Ray, Hit, AABB and the robust slab test shared by every structure.
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace ab {

using glm::vec3;

/// Positive infinity in single precision.
inline constexpr float kInf = std::numeric_limits<float>::infinity();
/// The id of "no triangle" and "no instance" in hits (contract: 0xFFFFFFFF).
inline constexpr uint32_t kInvalidId = 0xFFFFFFFFu;

/// A ray: origin, direction (not necessarily normalized, may have zero components), and the
/// parametric interval [tmin, tmax] in units of that direction. Layout matches the .rays record.
struct Ray {
  vec3 org{0.0f};
  vec3 dir{0.0f, 0.0f, 1.0f};
  float tmin = 0.0f;
  float tmax = kInf;
};
static_assert(sizeof(Ray) == 32);

/// The closest hit of a ray. Layout matches the .hits record. A miss has t = +inf and invalid ids.
struct Hit {
  float t = kInf;
  uint32_t prim = kInvalidId;
  uint32_t inst = kInvalidId;
  float u = 0.0f;
  float v = 0.0f;

  /// True when the record describes a hit.
  bool found() const { return prim != kInvalidId; }
};
static_assert(sizeof(Hit) == 20);

/// The one acceptance rule every structure uses: a candidate replaces the best when it is
/// strictly closer, or equally close with a lower (inst, prim) pair.
inline bool is_better_hit(float t, uint32_t inst, uint32_t prim, const Hit& best) {
  if (t != best.t) return t < best.t;
  if (inst != best.inst) return inst < best.inst;
  return prim < best.prim;
}

/// Axis-aligned box; the default is empty (lo = +inf, hi = -inf).
struct AABB {
  vec3 lo{kInf};
  vec3 hi{-kInf};

  /// Grows the box to contain point p.
  void extend(const vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  /// Grows the box to contain box b.
  void extend(const AABB& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  /// True when the box contains no point.
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  /// Edge lengths (zero vector for an empty box).
  vec3 extent() const { return empty() ? vec3(0.0f) : hi - lo; }
  /// Midpoint.
  vec3 center() const { return 0.5f * (lo + hi); }
  /// Surface area (0 for an empty box).
  float area() const {
    const vec3 e = extent();
    return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
  }
  /// Index of the longest axis.
  int longest_axis() const {
    const vec3 e = extent();
    return (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
  }
  /// Intersection of two boxes (may be empty).
  static AABB intersection(const AABB& a, const AABB& b) { return {glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)}; }
  /// True when the boxes share at least one point (touching counts).
  bool overlaps(const AABB& b) const {
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z &&
           b.lo.z <= hi.z;
  }
  /// True when p lies inside or on the box.
  bool contains(const vec3& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
};

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
inline float widen_near(float t) { return t * (t > 0.0f ? 1.0f - kBoxEps : 1.0f + kBoxEps); }
/// Widens a far distance towards +inf (conservative).
inline float widen_far(float t) { return t * (t > 0.0f ? 1.0f + kBoxEps : 1.0f - kBoxEps); }

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

}  // namespace ab
