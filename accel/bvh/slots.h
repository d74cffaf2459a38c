// The gapped slot array the three BVH builders fill in parallel, and its compaction (flatten.cpp) into the
// final depth-first node array.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "accel/bvh/build.h"
#include "accel/bvh/node.h"
#include "accel/core/aabb.h"

namespace ab {

/// Slots of a binary tree under construction. The node of range [b, e) sits at slot p; when split at m its
/// left child is at p + 1 and its right child at p + 2 (m - b), so disjoint subtrees never share a slot and
/// can be built in parallel. A leaf stores offset b and count e - b; an interior node the right child's
/// slot in offset and count 0. 2N - 1 slots hold any tree over N primitives.
struct BvhSlots {
  size_t size;                       ///< 2N - 1 (0 for no primitives)
  std::unique_ptr<BvhNode[]> slots;  ///< uninitialized: only the slots of the tree are written and read

  /// Room for a tree over n primitives.
  explicit BvhSlots(size_t n)
      : size(n == 0 ? 0 : 2 * n - 1), slots(std::make_unique_for_overwrite<BvhNode[]>(size)) {}
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

/// Compacts the slots into the final array (root at 0, padding at 1, sibling pairs in depth-first order);
/// order[k] is the id of the k-th primitive in leaf order.
BvhBuildResult flatten_bvh_slots(const BvhSlots& slots, std::vector<uint32_t> order);

}  // namespace ab
