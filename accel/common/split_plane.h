// Where a ray's parameter interval goes at a split plane: the one robust front-to-back step shared by
// the k-d trees, the octree (three mid-planes per node) and the BSP tree (arbitrary planes).
//
// The classic recursive traversal (Kaplan 1985; Havran 2000, "Heuristic ray shooting algorithms", TA_B rec)
// splits the interval [t0, t1] at t_split = (split - org) / dir into a near part and a far part. Written
// here so that it never loses a hit to rounding: both halves are widened around t_split like the slab test
// widens box distances (geometry.h), a ray parallel to the plane stays on its side, and a ray lying in the
// plane (or a NaN t_split) visits both sides over the whole interval. The near side is chosen by the sign
// of the direction (not by the origin), so negative tmin and origins behind the plane need no special case.
#pragma once

#include "accel/core/box_test.h"

#include <algorithm>
#include <cmath>

namespace ab {

/// How a ray interval [t0, t1] continues at a split plane.
struct PlaneVisit {
  bool first_below = true;    ///< the below (negative) side is met first along the ray
  bool visit_first = false;   ///< the first side overlaps [t0, t1]
  bool visit_second = false;  ///< the second side overlaps [t0, t1]
  float first_t1 = 0.0f;      ///< exit of the first side (widened)
  float second_t0 = 0.0f;     ///< entry of the second side (widened)
};

/// Splits [t0, t1] at a plane given the signed distance of the origin from it (`org_dist`, negative on
/// the below side), the rate of change of that distance along the ray (`rate`, the direction's component
/// along the normal), t_split and the half-width `widen` of the uncertain band around t_split.
/// `in_plane_band` is how close to the plane a parallel ray counts as lying in it.
[[gnu::always_inline]] inline PlaneVisit split_interval(float org_dist, float rate, float t_split, float widen, float in_plane_band,
                                 float t0, float t1) {
  PlaneVisit v;
  if (rate == 0.0f || t_split != t_split) {
    v.first_below = !(org_dist > 0.0f);
    v.visit_first = true;
    v.visit_second = !(std::fabs(org_dist) > in_plane_band);
    v.first_t1 = t1;
    v.second_t0 = t0;
    return v;
  }
  v.first_below = rate > 0.0f;
  v.first_t1 = std::min(t1, t_split + widen);
  v.second_t0 = std::max(t0, t_split - widen);
  v.visit_first = t0 <= v.first_t1;
  v.visit_second = v.second_t0 <= t1;
  return v;
}

/// A ray's origin, direction and reciprocal direction as plain arrays (indexing a glm vector by a
/// run-time axis goes through a switch).
struct RayAxes {
  float org[3], dir[3], inv[3];

  /// From ray r.
  explicit RayAxes(const Ray& r)
      : org{r.org.x, r.org.y, r.org.z},
        dir{r.dir.x, r.dir.y, r.dir.z},
        inv{1.0f / r.dir.x, 1.0f / r.dir.y, 1.0f / r.dir.z} {}
};

/// The axis-aligned case (k-d trees, octree): plane coordinate `split` on an axis where the ray has
/// origin `org`, direction `dir` and reciprocal `inv`. The band is relative (kBoxEps), as in slab_test.
[[gnu::always_inline]] inline PlaneVisit split_at_axis_plane(float org, float dir, float inv, float split, float t0, float t1) {
  const float t_split = (split - org) * inv;
  return split_interval(org - split, dir, t_split, std::fabs(t_split) * kBoxEps, 0.0f, t0, t1);
}

/// Where a ray crosses an axis-aligned plane: the widened crossing distances (near <= far, both NaN for a
/// ray lying in the plane) and which side it meets first.
struct AxisCrossing {
  float near, far;   ///< widen_near(t_split), widen_far(t_split)
  bool below_first;  ///< the below side comes first (direction's sign bit clear)
};

/// A ray prepared for many axis-aligned plane steps (the k-d tree's inner loop, after pbrt's
/// KdTreeAggregate): origin, reciprocal direction, the side met first and a positional band, per axis.
/// The crossing is widened relatively (kBoxEps, as slab_test) and by `margin` in position (margin / |dir|
/// in t): the kernel may accept a hit a few ulps of the coordinates outside a triangle that touches the
/// plane and was placed on one side only, and near t = 0 a relative widening is no widening at all. The
/// near side comes from the sign bit of the direction. A zero component gives t_split = +-inf (the ray
/// stays on its side) unless the origin lies within the margin of the plane: then both sides are visited
/// over the whole interval (NaN crossings: std::max(t0, NaN) is t0 and std::min(t1, NaN) is t1).
struct AxisRay {
  float org[3], inv[3], band[3];
  bool below_first[3], parallel[3];
  float margin;

  /// From ray r and the positional margin of the tree.
  AxisRay(const Ray& r, float margin_)
      : org{r.org.x, r.org.y, r.org.z},
        inv{1.0f / r.dir.x, 1.0f / r.dir.y, 1.0f / r.dir.z},
        below_first{!std::signbit(r.dir.x), !std::signbit(r.dir.y), !std::signbit(r.dir.z)},
        margin(margin_) {
    for (int a = 0; a < 3; ++a) {
      parallel[a] = !(std::fabs(inv[a]) < kInf);
      band[a] = parallel[a] ? 0.0f : margin * std::fabs(inv[a]);
    }
  }

  /// The crossing of plane coordinate `split` on axis a.
  [[gnu::always_inline]] AxisCrossing cross(int a, float split) const {
    const float t = (split - org[a]) * inv[a];
    if (parallel[a]) [[unlikely]] {
      if (std::fabs(split - org[a]) <= margin) return {std::nanf(""), std::nanf(""), below_first[a]};
      return {t, t, below_first[a]};
    }
    return {widen_near(t) - band[a], widen_far(t) + band[a], below_first[a]};
  }
};

}  // namespace ab
