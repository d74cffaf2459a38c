// The axis-aligned box every structure bounds its primitives and nodes with.
#pragma once

#include <algorithm>

#include "accel/core/ray.h"

namespace ab {

/// Surface area of a box with edge lengths e.
inline float area_of_extent(const vec3& e) {
  return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
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
  float area() const { return area_of_extent(extent()); }
  /// Index of the longest axis.
  int longest_axis() const {
    const vec3 e = extent();
    return (e.x >= e.y && e.x >= e.z) ? 0 : (e.y >= e.z ? 1 : 2);
  }
  /// Intersection of two boxes (may be empty).
  static AABB intersection(const AABB& a, const AABB& b) {
    return {glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)};
  }
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

}  // namespace ab
