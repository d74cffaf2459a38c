// Conservative insertion into the cells of a space-partitioning tree (DESIGN.md, "what keeps hits
// identical"): a primitive that touches a cell or lies within rounding of a split plane goes to every such
// cell. The margin is the width of that band; the builders track each primitive by its part inside the cell
// (its perfect-split bounds, Wald and Havran 2006), clipped into the child box grown by the margin.
#pragma once

#include <algorithm>

#include "accel/core/aabb.h"

namespace ab {

/// Margin of conservative insertion for a node box: a primitive within it of a split plane goes to both
/// children. Same scale as inflate_for_insertion (clip.h): relative to the box's size and position. The
/// traversals widen every plane crossing by it (PlaneRay), so it also covers the kernel's rounding there.
inline float insertion_margin(const AABB& box) {
  const vec3 e = box.extent();
  const vec3 a = glm::max(glm::abs(box.lo), glm::abs(box.hi));
  return std::max({e.x, e.y, e.z, a.x, a.y, a.z}) * 0x1p-18f;
}

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
