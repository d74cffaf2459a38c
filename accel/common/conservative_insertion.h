// Conservative insertion into the cells of a space-partitioning tree (DESIGN.md, "what keeps hits
// identical"): a primitive that touches a cell or lies within rounding of a split plane goes to every such
// cell. The margin is the width of that band; the builders track each primitive by its part inside the cell
// (its perfect-split bounds, Wald and Havran 2006), clipped into the child box grown by the margin.
#pragma once

#include <algorithm>
#include <limits>

#include "accel/core/aabb.h"

namespace ab {

/// Margin of conservative insertion for a node box: a primitive within it of a split plane goes to both
/// children, relative to the box's size and position (InsertionMargin below bounds it by the root's). The
/// traversals widen every plane crossing by it (PlaneRay), so it also covers the kernel's rounding there.
inline float insertion_margin(const AABB& box) {
  const vec3 e = box.extent();
  const vec3 a = glm::max(glm::abs(box.lo), glm::abs(box.hi));
  return std::max({e.x, e.y, e.z, a.x, a.y, a.z}) * 0x1p-18f;
}

/// True for a tree whose root box lies far from the origin: its largest coordinate exceeds 8 times its
/// largest extent (a mesh moved to 1e6, say). Such trees get the far rules (InsertionMargin; the bsp's
/// frame at the root's centre); every other tree is built as before them, bit for bit.
inline bool far_from_origin(const AABB& root) {
  if (root.empty()) return false;
  const vec3 e = root.extent(), a = glm::max(glm::abs(root.lo), glm::abs(root.hi));
  return std::max({a.x, a.y, a.z}) > 8.0f * std::max({e.x, e.y, e.z});
}

/// The insertion margin of one tree, made from its root box (issue 11, geometry far from the origin).
/// insertion_margin() scales with the box's coordinates, 32-64 ulps of them: at 1e6 that is 3.8, wider than
/// a whole mesh of a few units there, and every cell then holds most of it. What the margin covers splits
/// in two. The builders' clipping rounds clipped points to the coordinates, a few ulps of them (4-8 ulps:
/// 2^-21 of the box's magnitude). The kernel's own rounding does not grow with the coordinates: it computes
/// from org - v0 and the edges, so it scales with the ray's distance (the walks' relative widening,
/// kBoxEps) and with the edges, at most the root's extent (2^-18 of it, the old margin's scale). So for a
/// tree far from the origin (far_from_origin) the margin is min(insertion_margin(box), max(2^-18 root
/// extent, 2^-21 box magnitude)): 8 times or more smaller than before, and never larger than the root's
/// own, so the walks' band (the root's) still covers every node's margin. Any other tree keeps
/// insertion_margin().
class InsertionMargin {
 public:
  /// The box's own rule, insertion_margin() (no root).
  InsertionMargin() = default;
  /// The rule of a tree whose root box is `root`.
  explicit InsertionMargin(const AABB& root) {
    const vec3 e = root.extent();
    if (far_from_origin(root)) extent_term_ = std::max({e.x, e.y, e.z}) * 0x1p-18f;
  }
  /// The margin of node box `box`.
  float of(const AABB& box) const {
    const vec3 a = glm::max(glm::abs(box.lo), glm::abs(box.hi));
    return std::min(insertion_margin(box), std::max(extent_term_, std::max({a.x, a.y, a.z}) * 0x1p-21f));
  }
  /// `box` grown by its margin on every side.
  AABB inflate(const AABB& box) const {
    const vec3 m(of(box));
    return {box.lo - m, box.hi + m};
  }

 private:
  float extent_term_ = std::numeric_limits<float>::infinity();
};

/// The part of primitive i that a child box holds for the builders: its perfect-split bounds in the child
/// box grown by `margin`, clamped back into the child box (so a primitive that only comes within the
/// margin becomes a flat sliver on the child's face instead of disappearing).
template <class P>
AABB clip_into_child(const P& prims, uint32_t i, const AABB& child, float margin) {
  const AABB grown{child.lo - vec3(margin), child.hi + vec3(margin)};
  AABB cb = prims.clipped_bounds(i, grown);
  if (cb.empty()) cb = AABB::intersection(prims.bounds(i), grown);
  cb.lo = glm::clamp(cb.lo, child.lo, child.hi);
  cb.hi = glm::clamp(cb.hi, child.lo, child.hi);
  cb.lo = glm::min(cb.lo, cb.hi);
  return cb;
}

}  // namespace ab
