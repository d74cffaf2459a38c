// The node of the binary BVH: 32 bytes, siblings paired in one 64-byte line.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/common/cache_line_allocator.h"
#include "accel/core/aabb.h"

namespace ab {

/// Largest allowed max_depth (the traversal stacks hold one entry per level).
inline constexpr int kBvhMaxDepth = 120;

/// One flattened BVH node. Interior (count == 0): the children are the sibling pair `offset`, `offset + 1`
/// (one 64-byte line, so one fetch gives both boxes for the two-box test). Leaf (count > 0): primitives
/// [offset, offset + count) of the leaf-ordered reference array. The layout (lo, offset, hi, count) lets
/// a node load as one 32-byte vector. Node 0 is the root, node 1 is padding, pairs start at 2.
struct alignas(32) BvhNode {
  float lo[3];      ///< box minimum
  uint32_t offset;  ///< interior: the children's pair; leaf: the first primitive of leaf order
  float hi[3];      ///< box maximum
  uint32_t count;   ///< primitives of a leaf, 0 for an interior node

  /// True for a leaf.
  bool is_leaf() const { return count > 0; }
  /// The node's box.
  AABB box() const { return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}; }
};
static_assert(sizeof(BvhNode) == 32, "BVH nodes are 32 bytes");

/// The node array of a binary BVH.
using BvhNodeArray = std::vector<BvhNode, CacheLineAllocator<BvhNode>>;

}  // namespace ab
