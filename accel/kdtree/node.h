// The compact k-d tree node (8 bytes, as in pbrt: Pharr, Jakob and Humphreys, "Physically Based Rendering",
// section 4.4), shared by both k-d builders and the traversal.
#pragma once

#include <tbb/parallel_invoke.h>

#include <bit>
#include <cstdint>

#include "accel/common/tree_buffer.h"

namespace ab {

/// One k-d tree node: an interior node (axis, split coordinate, index of the above child, and a flag per
/// child that is an empty leaf; the below child, when not empty, follows it directly) or a leaf (offset and
/// count of its primitive indices). Empty children are flags rather than nodes (drop_empty_leaves), so the
/// traversal never visits or stacks them.
class KdNode {
 public:
  /// A leaf of `count` primitive indices starting at `first`.
  static KdNode leaf(uint32_t first, uint32_t count) { return KdNode(first, (count << 2) | 3u); }
  /// An interior node splitting `axis` at `split`; the above child is node `above`; a child flagged
  /// empty has no node.
  static KdNode interior(int axis, float split, uint32_t above, bool below_empty = false,
                         bool above_empty = false) {
    return KdNode(std::bit_cast<uint32_t>(split), (above << 4) | (uint32_t(above_empty) << 3) |
                                                      (uint32_t(below_empty) << 2) | uint32_t(axis));
  }

  /// True for a leaf.
  bool is_leaf() const { return (bits_ & 3u) == 3u; }
  /// Split axis (interior nodes).
  int axis() const { return int(bits_ & 3u); }
  /// Split coordinate (interior nodes).
  float split() const { return std::bit_cast<float>(word_); }
  /// Index of the above child (interior nodes); the below child is this node's index + 1.
  uint32_t above() const { return bits_ >> 4; }
  /// True when the below child is an empty leaf (interior nodes).
  bool below_empty() const { return (bits_ & 4u) != 0; }
  /// True when the above child is an empty leaf (interior nodes).
  bool above_empty() const { return (bits_ & 8u) != 0; }
  /// First primitive index (leaves).
  uint32_t first() const { return word_; }
  /// Number of primitives (leaves).
  uint32_t count() const { return bits_ >> 2; }
  /// Moves the node's indices by `offsets` (TreeBuffer::splice).
  void rebase(const TreeOffsets& offsets) {
    if (is_leaf()) {
      word_ += offsets.ref;
    } else {
      bits_ += offsets.node << 4;
    }
  }
  /// This interior node with another above child and empty-child flags (drop_empty_leaves).
  KdNode relinked(uint32_t above, bool below_empty, bool above_empty) const {
    return interior(axis(), split(), above, below_empty, above_empty);
  }
  /// Largest node index an interior node can hold.
  static constexpr uint32_t kMaxIndex = (1u << 28) - 1;

 private:
  KdNode(uint32_t word, uint32_t bits) : word_(word), bits_(bits) {}
  uint32_t word_;
  uint32_t bits_;
};
static_assert(sizeof(KdNode) == 8);

/// The nodes and leaf references a k-d builder writes (depth-first: the below child next to its parent).
using KdBuffer = TreeBuffer<KdNode>;

/// Builds the two subtrees of the interior node at out.nodes[self] (a placeholder): below(buffer) writes
/// the below subtree, above(buffer) the above one. In parallel, the below subtree is still written into
/// out directly and only the above one into a buffer of its own, appended after it: the serial layout, so
/// the same tree for any thread count, and each subtree copied once per level of parallel ancestors at most.
template <class Below, class Above>
void build_kd_children(KdBuffer& out, size_t self, int axis, float split, bool parallel, Below&& below,
                       Above&& above) {
  if (!parallel) {
    below(out);
    out.nodes[self] = KdNode::interior(axis, split, uint32_t(out.nodes.size()));
    above(out);
    return;
  }
  KdBuffer above_buffer;
  tbb::parallel_invoke([&] { below(out); }, [&] { above(above_buffer); });
  out.nodes[self] = KdNode::interior(axis, split, uint32_t(out.nodes.size()));
  out.append(above_buffer);
}

}  // namespace ab
