// What the two SAH builders (binned, sweep) do with the split their search found: the split itself and the
// decision between a leaf, that split and a forced split in the middle.
#pragma once

#include <cstdint>

#include "accel/bvh/config.h"
#include "accel/core/aabb.h"

namespace ab {

/// Result of a split search: axis, position (a bin boundary or a sorted index) and SAH cost.
struct SahSplit {
  int axis = -1;      ///< -1: no valid split found
  int position = 0;   ///< bins [0, position) go left (binned), or sorted index split (sweep)
  float cost = kInf;  ///< SAH cost of the split (SahCosts::split with the builder's costs)
};

/// True when a node of n primitives becomes a leaf whatever its split search would find, so the search can
/// be skipped: n fits a leaf and the traversal cost alone is at least the leaf's cost. A split's cost is
/// the traversal cost plus a sum of non-negative terms (its two sides are never empty), so it is never below
/// the traversal cost, and sah_decision would make the same leaf. With blocks of four (width 8) this is every
/// node of two to four primitives.
inline bool leaf_without_search(uint32_t n, const BvhSahTreeConfig& config) {
  return n <= uint32_t(config.max_leaf_size) && config.costs.traversal >= config.costs.leaf(n);
}

/// Leaf or split after an SAH search over a node of n primitives: returns 0 for a leaf, n / 2 for a forced
/// split in the middle (no valid split but too many primitives for a leaf), and n for "split as found".
/// A leaf is made when the SAH says splitting does not pay and the node holds at most max_leaf_size.
inline uint32_t sah_decision(uint32_t n, const SahSplit& best, const BvhSahTreeConfig& config) {
  const bool small = n <= uint32_t(config.max_leaf_size);
  if (best.axis < 0) return small ? 0 : n / 2;
  if (small && best.cost >= config.costs.leaf(n)) return 0;
  return n;
}

}  // namespace ab
