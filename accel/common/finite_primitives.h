// Primitives with NaN or infinite coordinates have no place in a subdivision of space: they are kept
// apart (tested for every ray, so their ids and any hit they give are kept) and the tree is built over
// the others.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "accel/core/aabb.h"

namespace ab {

/// True when every coordinate of b is finite and b is not empty.
inline bool finite_box(const AABB& b) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(b.lo[a]) || !std::isfinite(b.hi[a])) return false;
  return !b.empty();
}

/// Splits the primitives of `prims` into those with finite bounds (returned; their union goes into `box`)
/// and the rest (`unbounded`: tested for every ray, so their ids and any hit are kept).
template <class P>
std::vector<uint32_t> partition_finite(const P& prims, std::vector<uint32_t>& unbounded, AABB& box) {
  std::vector<uint32_t> ids;
  unbounded.clear();
  box = AABB{};
  for (size_t i = 0; i < prims.size(); ++i) {
    const AABB b = prims.bounds(i);
    if (finite_box(b)) {
      ids.push_back(uint32_t(i));
      box.extend(b);
    } else {
      unbounded.push_back(uint32_t(i));
    }
  }
  return ids;
}

}  // namespace ab
