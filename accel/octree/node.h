// The octree's node (8 bytes) and the child boxes that build and traversal both split the same way.
#pragma once

#include <cstdint>

#include "accel/common/tree_buffer.h"
#include "accel/core/aabb.h"

namespace ab {

/// One octree node (8 bytes): an interior node (index of the first of its eight consecutive children) or
/// a leaf (offset and count of its primitive indices).
class OctNode {
 public:
  /// A leaf of `count` primitive indices starting at `first`.
  static OctNode leaf(uint32_t first, uint32_t count) { return OctNode(first, count | kLeafBit); }
  /// An interior node whose children are nodes first_child .. first_child + 7 (child c has bit a of c set
  /// when it is the upper half along axis a).
  static OctNode interior(uint32_t first_child) { return OctNode(first_child, 0); }

  /// True for a leaf.
  bool is_leaf() const { return (bits_ & kLeafBit) != 0; }
  /// First child (interior) or first primitive index (leaf).
  uint32_t first() const { return word_; }
  /// Number of primitives (leaves).
  uint32_t count() const { return bits_ & ~kLeafBit; }
  /// Moves the node's indices by `offsets` (TreeBuffer::splice).
  void rebase(const TreeOffsets& offsets) { word_ += is_leaf() ? offsets.ref : offsets.node; }

 private:
  static constexpr uint32_t kLeafBit = 0x80000000u;
  OctNode(uint32_t word, uint32_t bits) : word_(word), bits_(bits) {}
  uint32_t word_;
  uint32_t bits_;
};
static_assert(sizeof(OctNode) == 8);

/// Box of child c of box b (bit a of c: upper half along axis a). Build and traversal use this same
/// arithmetic, so their planes are the same floats.
inline AABB octant_box(const AABB& b, int c) {
  AABB out = b;
  for (int a = 0; a < 3; ++a) {
    const float mid = 0.5f * (b.lo[a] + b.hi[a]);
    if ((c >> a) & 1)
      out.lo[a] = mid;
    else
      out.hi[a] = mid;
  }
  return out;
}

}  // namespace ab
