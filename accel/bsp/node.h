// The BSP tree's node (8 bytes; its plane is the tree buffer's payload) and the buffer a BSP builder writes.
#pragma once

#include <cstdint>

#include "accel/bsp/candidates.h"
#include "accel/common/tree_buffer.h"

namespace ab {

/// One BSP node (8 bytes): an interior node (index of its plane, index of the above child and a flag per
/// child that is an empty leaf; the below child, when not empty, follows it) or a leaf (offset and count
/// of its primitive indices). Empty children are flags, not nodes (drop_empty_leaves, empty_leaves.h).
class BspNode {
 public:
  /// A leaf of `count` primitive indices starting at `first`.
  static BspNode leaf(uint32_t first, uint32_t count) { return BspNode(first, (count << 1) | 1u); }
  /// An interior node split by plane `plane`, above child `above`.
  static BspNode interior(uint32_t plane, uint32_t above, bool below_empty = false,
                          bool above_empty = false) {
    return BspNode(plane, (above << 3) | (uint32_t(above_empty) << 2) | (uint32_t(below_empty) << 1));
  }

  /// True for a leaf.
  bool is_leaf() const { return bits_ & 1u; }
  /// Plane index (interior nodes).
  uint32_t plane() const { return word_; }
  /// Above child (interior nodes); the below child is this node's index + 1.
  uint32_t above() const { return bits_ >> 3; }
  /// True when the below child is an empty leaf (interior nodes).
  bool below_empty() const { return (bits_ & 2u) != 0; }
  /// True when the above child is an empty leaf (interior nodes).
  bool above_empty() const { return (bits_ & 4u) != 0; }
  /// First primitive index (leaves).
  uint32_t first() const { return word_; }
  /// Primitive count (leaves).
  uint32_t count() const { return bits_ >> 1; }
  /// Moves the node's indices by `offsets` (TreeBuffer::splice; the planes are the payload).
  void rebase(const TreeOffsets& offsets) {
    if (is_leaf()) {
      word_ += offsets.ref;
    } else {
      word_ += offsets.payload;
      bits_ += offsets.node << 3;
    }
  }
  /// This interior node with another above child and empty-child flags (drop_empty_leaves).
  BspNode relinked(uint32_t above, bool below_empty, bool above_empty) const {
    return interior(plane(), above, below_empty, above_empty);
  }
  /// Largest node index an interior node can hold.
  static constexpr uint32_t kMaxIndex = (1u << 29) - 1;

 private:
  BspNode(uint32_t word, uint32_t bits) : word_(word), bits_(bits) {}
  uint32_t word_;
  uint32_t bits_;
};
static_assert(sizeof(BspNode) == 8);

/// Nodes, planes (one per interior node, which indexes it) and leaf references of a BSP tree.
using BspBuffer = TreeBuffer<BspNode, BspPlane>;

}  // namespace ab
