// Linear bounds for the motion BVH: a box whose corners move linearly over a time range (Embree's LBBox),
// and each primitive's boxes at its time steps, from which a conservative linear bound over any time range
// is fitted.
#pragma once

#include <algorithm>
#include <cstdint>

#include "accel/core/aabb.h"
#include "accel/core/instances.h"
#include "accel/core/motion_prims.h"
#include "accel/core/primitives.h"

namespace ab {

/// A box moving linearly from `at0` (start of a time range) to `at1` (its end).
struct LinearBounds {
  AABB at0, at1;

  /// The box at fraction f of the range.
  AABB at(float f) const { return {(1.0f - f) * at0.lo + f * at1.lo, (1.0f - f) * at0.hi + f * at1.hi}; }
  /// Grows to hold b over the whole range (end by end: the line through the lower ends lies below both).
  void extend(const LinearBounds& b) {
    at0.extend(b.at0);
    at1.extend(b.at1);
  }
  /// The box halfway, whose area the SAH uses (Embree's expected half area of a linear box).
  AABB middle() const { return at(0.5f); }
  /// A box holding the bound over the whole range.
  AABB hull() const {
    AABB b = at0;
    b.extend(at1);
    return b;
  }
};

/// Time steps of primitive i (1 when it does not move) and its box at step k, per primitive set.
inline uint32_t motion_steps(const TrianglePrims&, size_t) {
  return 1;
}
inline AABB step_bounds(const TrianglePrims& p, size_t i, uint32_t) {
  return p.bounds(i);
}
inline uint32_t motion_steps(const MotionTrianglePrims& p, size_t i) {
  return p.moves(i) ? p.steps() : 1;
}
inline AABB step_bounds(const MotionTrianglePrims& p, size_t i, uint32_t k) {
  return p.moves(i) ? p.triangle_step(i, k).bounds() : p.bounds(i);
}
inline uint32_t motion_steps(const InstancePrims& p, size_t i) {
  const Instance& inst = p.instance(i);
  return inst.moves() ? static_cast<uint32_t>(inst.to_world_steps.size()) : 1;
}
inline AABB step_bounds(const InstancePrims& p, size_t i, uint32_t k) {
  return p.instance(i).moves() ? instance_step_bounds(p.instance(i), k) : p.bounds(i);
}

/// The box of primitive i at time t in [0, 1] (its step boxes interpolated per segment).
template <class P>
AABB box_at_time(const P& p, size_t i, float t) {
  const uint32_t steps = motion_steps(p, i);
  if (steps == 1) return step_bounds(p, i, 0);
  const MotionSegment seg = motion_segment(t, steps);
  return LinearBounds{step_bounds(p, i, seg.index), step_bounds(p, i, seg.index + 1)}.at(seg.fraction);
}

/// A linear bound of primitive i over [t0, t1]: the boxes at both ends, both ends pushed out by how far the
/// line misses each time step inside the range (the primitive's box moves linearly between steps, so a line
/// holding it at the range's ends and at every step inside holds it throughout).
template <class P>
LinearBounds prim_linear_bounds(const P& p, size_t i, float t0, float t1) {
  LinearBounds lb{box_at_time(p, i, t0), box_at_time(p, i, t1)};
  const uint32_t steps = motion_steps(p, i);
  if (steps == 1 || lb.at0.empty()) return lb;
  const auto first = static_cast<uint32_t>(t0 * float(steps - 1)) + 1;
  for (uint32_t k = first; k + 1 < steps && float(k) / float(steps - 1) < t1; ++k) {
    const float f = (float(k) / float(steps - 1) - t0) / (t1 - t0);
    const AABB line = lb.at(f), box = step_bounds(p, i, k);
    const vec3 down = glm::max(line.lo - box.lo, vec3(0.0f)), up = glm::max(box.hi - line.hi, vec3(0.0f));
    lb.at0 = {lb.at0.lo - down, lb.at0.hi + up};
    lb.at1 = {lb.at1.lo - down, lb.at1.hi + up};
  }
  return lb;
}

}  // namespace ab
