// The gapped slot array the three BVH builders fill in parallel, and its compaction (flatten.cpp) into the
// final depth-first node array.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "accel/bvh/build.h"
#include "accel/bvh/node.h"
#include "accel/core/aabb.h"

namespace ab {

/// Slots of a binary tree under construction. The node of range [b, e) sits at slot p; when split at m its
/// left child is at p + 1 and its right child at p + 2 (m - b), so disjoint subtrees never share a slot and
/// can be built in parallel (a subtree built serially may instead put its right child right after its left
/// subtree: set_right). A leaf stores offset b and count e - b; an interior node the right child's
/// slot in offset and count 0. 2N - 1 slots hold any tree over N primitives.
struct BvhSlots {
  size_t size;  ///< 2N - 1 (0 for no primitives)
  /// Uninitialized: only the slots of the tree are written and read. Ordinary pages (not huge_pages.h):
  /// the binned builder leaves most of the room untouched, and untouched 4 KiB pages are never zeroed.
  std::unique_ptr<BvhNode[]> slots;

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
  /// Makes slot p an interior node whose right child is at slot `right` (a builder that lays a subtree out
  /// compactly puts it right after the left child's subtree).
  void set_right(uint32_t p, uint32_t right) {
    slots[p].offset = right;
    slots[p].count = 0;
  }
  /// Makes slot p (range starting at b) an interior node split at m; returns the right child's slot.
  uint32_t set_interior(uint32_t p, uint32_t b, uint32_t m) {
    slots[p].offset = p + 2 * (m - b);
    slots[p].count = 0;
    return slots[p].offset;
  }
};

/// A binned SAH build (binned.cpp) as its builder leaves it: the slots, root at slot 0, and the leaf order.
struct BvhSlotsResult {
  BvhSlots slots;               ///< the tree (size 0 for no primitives)
  std::vector<uint32_t> order;  ///< order[k]: id of the k-th primitive in leaf order
};

/// The binned SAH build without the flattening (binned.cpp; build_bvh flattens this result), for the
/// greedy collapse straight from the slots (collapse.h).
BvhSlotsResult build_bvh_slots(const BvhSahConfig& config, std::span<const AABB> bounds);

/// Writes the bounds of primitives [begin, end) to out[0, end - begin); called in parallel on disjoint
/// ranges of at most kBoundsBlock primitives.
using PrimBoundsSource = std::function<void(size_t begin, size_t end, AABB* out)>;
/// The largest range a PrimBoundsSource is asked for.
inline constexpr size_t kBoundsBlock = 512;

/// The same build over n primitives whose bounds come from `bounds` block by block, straight into the
/// builder's references (no array of all the bounds is made, written and read again).
BvhSlotsResult build_bvh_slots(const BvhSahConfig& config, size_t n, const PrimBoundsSource& bounds);

/// A slot tree (not empty) as the one statistics walk (accel/common/tree_stats.h) sees it: the same
/// nodes in the same order as BvhTreeVisitor over its flattened array.
struct BvhSlotsVisitor {
  using Node = uint32_t;  ///< slot index
  const BvhSlots& tree;   ///< the slots

  /// Slot 0.
  Node root() const { return 0; }
  /// The node's box.
  AABB box(Node i) const { return tree.slots[i].box(); }
  /// True for a leaf.
  bool is_leaf(Node i) const { return tree.slots[i].is_leaf(); }
  /// Primitives of a leaf.
  uint32_t count(Node i) const { return tree.slots[i].count; }
  /// The children, right first: the walk pops the last child first, so it goes left to right.
  template <class F>
  void children(Node i, F&& f) const {
    f(tree.slots[i].offset);
    f(i + 1);
  }
};

/// Compacts the slots into the final array (root at 0, padding at 1, sibling pairs in depth-first order);
/// order[k] is the id of the k-th primitive in leaf order.
BvhBuildResult flatten_bvh_slots(const BvhSlots& slots, std::vector<uint32_t> order);

}  // namespace ab
