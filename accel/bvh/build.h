// What the three BVH builders (object median in bvh.cpp, binned SAH in bvh_binned.cpp, full-sweep SAH in
// bvh_sweep.cpp) share: the gapped slot array they fill in parallel, the leaf-or-split decision after an SAH search, and
// the compaction of the slots into the final depth-first node array with its statistics.
#pragma once

#include "accel/bvh/bvh.h"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace ab {

/// Slots of a binary tree under construction. The node of range [b, e) sits at slot p; when split at m its
/// left child is at p + 1 and its right child at p + 2 (m - b), so disjoint subtrees never share a slot and
/// can be built in parallel. A leaf stores offset b and count e - b; an interior node the right child's
/// slot in offset and count 0. 2N - 1 slots hold any tree over N primitives.
struct BvhSlots {
  size_t size;                       ///< 2N - 1 (0 for no primitives)
  std::unique_ptr<BvhNode[]> slots;  ///< uninitialized: only the slots of the tree are written and read

  /// Room for a tree over n primitives.
  explicit BvhSlots(size_t n) : size(n == 0 ? 0 : 2 * n - 1), slots(std::make_unique_for_overwrite<BvhNode[]>(size)) {}
  /// Writes the box of slot p.
  void set_box(uint32_t p, const AABB& box) {
    for (int a = 0; a < 3; ++a) {
      slots[p].lo[a] = box.lo[a];
      slots[p].hi[a] = box.hi[a];
    }
  }
  /// Makes slot p a leaf over [b, e).
  void set_leaf(uint32_t p, uint32_t b, uint32_t e) {
    slots[p].offset = b;
    slots[p].count = e - b;
  }
  /// Makes slot p (range starting at b) an interior node split at m; returns the right child's slot.
  uint32_t set_interior(uint32_t p, uint32_t b, uint32_t m) {
    slots[p].offset = p + 2 * (m - b);
    slots[p].count = 0;
    return slots[p].offset;
  }
};

/// Leaf or split after an SAH search over a node of n primitives: returns 0 for a leaf, n / 2 for a forced
/// split in the middle (no valid split but too many primitives for a leaf), and n for "split as found".
/// A leaf is made when the SAH says splitting does not pay and the node holds at most max_leaf_size.
inline uint32_t sah_decision(uint32_t n, const SahSplit& best, const BvhConfig& config) {
  const bool small = n <= uint32_t(config.max_leaf_size);
  if (best.axis < 0) return small ? 0 : n / 2;
  if (small && best.cost >= config.costs.leaf(n)) return 0;
  return n;
}

/// Compacts the slots into the final array (root at 0, padding at 1, sibling pairs in depth-first order)
/// and gathers the statistics; order[k] is the id of the k-th primitive in leaf order.
BvhBuildResult flatten_bvh_slots(const BvhSlots& slots, std::vector<uint32_t> order);

/// The binned SAH builder (bvh_binned.cpp). It bins the centres of the bounds, which is what both
/// primitive sets' centroid() returns.
BvhBuildResult build_bvh_binned(const BvhConfig& config, std::span<const AABB> bounds);

/// The full-sweep SAH builder (bvh_sweep.cpp).
BvhBuildResult build_bvh_sweep(const BvhConfig& config, std::span<const AABB> bounds, std::span<const vec3> centroids);

}  // namespace ab
