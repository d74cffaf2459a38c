// The motion BVH's node: a linear bound over a time range (the boxes at the range's two ends, widened so
// that rounding never culls), the range, and either a leaf's references or the right child.
#pragma once

#include <cstdint>

#include "accel/bvh/motion_bounds.h"
#include "accel/core/box_test.h"

namespace ab {

/// Relative widening of a node's end boxes: 2^-18 of the largest magnitude of its corners per axis. The box
/// interpolated at a ray's time differs from the exact line by the rounding of a + f (b - a) and of f
/// (a few ulps of max |a|, |b|), and a primitive interpolated by its own segment fraction differs from its
/// exact position by a few ulps of its coordinates and of their motion (at most 2 max |a|, |b|): under 2^-20
/// of the magnitude together, so 2^-18 holds it four times over.
inline constexpr float kMotionBoxEps = 0x1p-18f;

struct MotionPairTest;

/// One node (64 bytes): the linear bound over [t0, t1] as its start box and the motion of its corners to the
/// end box (lo1 = lo0 + dlo; a static node's motion is 0 and its box at any time is exactly lo0, hi0).
/// Interior (count == 0): the children are the sibling pair `offset`, `offset + 1`; leaf (count > 0):
/// references [offset, offset + count), as BvhNode.
struct MotionBvhNode {
  using PairTest = MotionPairTest;  ///< the ray test of a sibling pair, for walk_bvh2

  vec3 lo0, hi0, dlo, dhi;
  float t0 = 0.0f, t1 = 1.0f;
  uint32_t offset = 0;
  uint32_t count = 0;

  /// A node over lb on [t0, t1], the end boxes widened by kMotionBoxEps (an interior node until set).
  static MotionBvhNode make(const LinearBounds& lb, float t0, float t1) {
    MotionBvhNode n;
    const vec3 mag = glm::max(glm::max(glm::abs(lb.at0.lo), glm::abs(lb.at0.hi)),
                              glm::max(glm::abs(lb.at1.lo), glm::abs(lb.at1.hi)));
    const vec3 m = mag * kMotionBoxEps;
    n.lo0 = lb.at0.lo - m, n.hi0 = lb.at0.hi + m;
    n.dlo = (lb.at1.lo - m) - n.lo0, n.dhi = (lb.at1.hi + m) - n.hi0;
    n.t0 = t0, n.t1 = t1;
    return n;
  }
  /// True for a leaf.
  bool is_leaf() const { return count > 0; }
  /// True when the node's range holds time t.
  bool holds(float t) const { return t >= t0 && t <= t1; }
  /// The box at time t (in the range).
  AABB box_at(float t) const {
    const float f = t0 == 0.0f && t1 == 1.0f ? t : (t - t0) / (t1 - t0);  // most nodes span the shutter
    return {lo0 + f * dlo, hi0 + f * dhi};
  }
  /// A box holding the node over its whole range.
  AABB hull() const { return {glm::min(lo0, lo0 + dlo), glm::max(hi0, hi0 + dhi)}; }
};
static_assert(sizeof(MotionBvhNode) == 64);

/// The slab test (Ize 2013, widened as BvhPairTest) of a sibling pair's boxes at the ray's time; a node whose
/// range does not hold the time is not entered.
struct MotionPairTest {
  /// Prepares the per-ray data.
  explicit MotionPairTest(const Ray& ray) : rd(ray), tmin(ray.tmin), time(ray.time) {}

  /// Entry distance of node n, or inf when the ray misses it before limit (or at another time).
  [[gnu::always_inline]] float entry(const MotionBvhNode& n, float limit) const {
    if (!n.holds(time)) return kInf;
    float t0 = tmin, t1 = limit;
    return slab_test(n.box_at(time), rd, t0, t1) ? t0 : kInf;
  }
  /// Entries of pair[0] and pair[1] into tl and tr.
  [[gnu::always_inline]] void entries(const MotionBvhNode* pair, float limit, float& tl, float& tr) const {
    tl = entry(pair[0], limit);
    tr = entry(pair[1], limit);
  }

  RayBoxData rd;  ///< origin, reciprocal direction, sign bits
  float tmin;     ///< the ray's tmin
  float time;     ///< the ray's time
};

}  // namespace ab
