// Where a ray's parameter interval goes at a split plane: the one robust front-to-back step of every
// spatial tree, for the k-d trees' axis planes, the octree's mid-planes and the BSP tree's arbitrary planes.
//
// The classic recursive traversal (Kaplan 1985; Havran 2000, "Heuristic ray shooting algorithms", TA_B rec)
// splits the interval [t0, t1] at t_split = (split - org) / dir into the part before the plane and the
// part after it. Written here so that it never loses a hit to rounding: the crossing is widened into
// [near, far] (relatively, as the slab test widens box distances (box_test.h), and by the tree's positional
// margin), the side met first keeps [t0, min(t1, far)] and the second side gets [max(t0, near), t1]. A ray
// parallel to the plane has an infinite crossing and stays on its side; a ray lying in the plane (within
// the margin) or a NaN crossing visits both sides over the whole interval. The side met first is chosen by
// the sign of the direction (not by the origin), so negative tmin and origins behind the plane need no
// special case. The ray is prepared once per traversal (PlaneRay, the tight form of pbrt's
// KdTreeAggregate: origin, reciprocal direction, first side and positional band per axis), so that an
// axis-aligned step costs a subtraction, a multiplication and a few comparisons.
#pragma once

#include <algorithm>
#include <cmath>

#include "accel/core/box_test.h"
#include "accel/core/ray.h"

namespace ab {

/// Where a ray crosses a plane: the widened crossing distances (near <= far, both NaN for a ray lying in
/// the plane) and which side it meets first. Its four members are the one plane step: the first side keeps
/// [t0, min(t1, far)] when far >= t0, the second gets [max(t0, near), t1] when near <= t1, so a NaN crossing
/// keeps both sides over the whole interval (the comparisons are false, std::min(t1, NaN) is t1 and
/// std::max(t0, NaN) is t0).
struct PlaneCrossing {
  float near, far;   ///< the crossing distance widened towards the origin and away from it
  bool below_first;  ///< the below side (negative distance from the plane) comes first along the ray

  /// True when the side met first overlaps [t0, ...].
  [[gnu::always_inline]] bool reaches_first(float t0) const { return !(far < t0); }
  /// True when the side met second overlaps [..., t1].
  [[gnu::always_inline]] bool reaches_second(float t1) const { return !(near > t1); }
  /// Exit of the first side from an interval ending at t1.
  [[gnu::always_inline]] float first_exit(float t1) const { return std::min(t1, far); }
  /// Entry of the second side into an interval starting at t0.
  [[gnu::always_inline]] float second_entry(float t0) const { return std::max(t0, near); }
};

/// How a ray interval [t0, t1] continues at a plane (the octree's cells, which carry their boxes along).
struct PlaneVisit {
  bool below_first;   ///< the below side is met first
  bool visit_first;   ///< the first side overlaps [t0, t1]
  bool visit_second;  ///< the second side overlaps [t0, t1]
  float first_t1;     ///< exit of the first side (widened)
  float second_t0;    ///< entry of the second side (widened)
};

/// The plane step of crossing x applied to [t0, t1], all at once.
[[gnu::always_inline]] inline PlaneVisit split_interval(const PlaneCrossing& x, float t0, float t1) {
  return {x.below_first, x.reaches_first(t0), x.reaches_second(t1), x.first_exit(t1), x.second_entry(t0)};
}

/// A ray prepared for many plane steps: per axis its origin, direction, reciprocal direction, the side met
/// first and the positional band, and the tree's positional margin. The margin is the tree's insertion
/// margin: the kernel may accept a hit a few ulps of the coordinates outside a triangle that touches the
/// plane and was placed on one side only, and near t = 0 a relative widening is no widening at all.
class PlaneRay {
 public:
  /// From ray r and the positional margin of the tree.
  PlaneRay(const Ray& r, float margin)
      : org_{r.org.x, r.org.y, r.org.z},
        dir_{r.dir.x, r.dir.y, r.dir.z},
        inv_{1.0f / r.dir.x, 1.0f / r.dir.y, 1.0f / r.dir.z},
        below_first_{!std::signbit(r.dir.x), !std::signbit(r.dir.y), !std::signbit(r.dir.z)},
        margin_(margin) {
    for (int a = 0; a < 3; ++a) {
      parallel_[a] = !(std::fabs(inv_[a]) < kInf);
      band_[a] = parallel_[a] ? 0.0f : margin * std::fabs(inv_[a]);
    }
  }

  /// The crossing of the axis-aligned plane at coordinate `split` on axis a (k-d trees, octree): widened
  /// relatively (kBoxEps, as slab_test) and by margin / |dir| in t. A zero component gives t = +-inf (the
  /// ray stays on its side) unless the origin lies within the margin of the plane: then NaN (both sides).
  [[gnu::always_inline]] PlaneCrossing cross(int a, float split) const {
    const float t = (split - org_[a]) * inv_[a];
    if (parallel_[a]) [[unlikely]] {
      if (std::fabs(split - org_[a]) <= margin_) return {std::nanf(""), std::nanf(""), below_first_[a]};
      return {t, t, below_first_[a]};
    }
    return {widen_near(t) - band_[a], widen_far(t) + band_[a], below_first_[a]};
  }

  /// The crossing of the plane dot(n, x) = d (BSP tree; n of unit length): t_split = -(n.o - d) / (n.dir),
  /// widened by a band that covers the margin and the rounding of n.o - d (relative to |d| and |n|.|o|),
  /// divided by |n.dir| into t, plus the relative kBoxEps. A ray parallel to the plane stays on its side
  /// unless its origin lies within that band (then NaN: both sides).
  [[gnu::always_inline]] PlaneCrossing cross(const vec3& n, float d) const {
    const float org_dist = dot(n, org_) - d;
    const float rate = dot(n, dir_);
    const float band = margin_ + (std::fabs(d) + dot(glm::abs(n), abs_org())) * 0x1p-20f;
    const float t_split = -org_dist / rate;
    if (rate == 0.0f) [[unlikely]] {
      if (!(std::fabs(org_dist) > band)) return {std::nanf(""), std::nanf(""), !std::signbit(rate)};
      return {t_split, t_split, !std::signbit(rate)};
    }
    const float widen = band / std::fabs(rate) + std::fabs(t_split) * kBoxEps;
    return {t_split - widen, t_split + widen, rate > 0.0f};
  }

 private:
  /// glm::dot's order of operations, on an array: (x + y) + z.
  static float dot(const vec3& n, const float* v) { return n.x * v[0] + n.y * v[1] + n.z * v[2]; }
  static float dot(const vec3& n, const vec3& v) { return n.x * v.x + n.y * v.y + n.z * v.z; }
  vec3 abs_org() const { return {std::fabs(org_[0]), std::fabs(org_[1]), std::fabs(org_[2])}; }

  float org_[3], dir_[3], inv_[3], band_[3];
  bool below_first_[3], parallel_[3];
  float margin_;
};

}  // namespace ab
