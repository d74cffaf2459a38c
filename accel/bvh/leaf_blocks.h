// The leaves of the 8-wide BVH over triangles as blocks of four triangles (Embree's Triangle4 layout), which
// the four-lane kernel tests at once (leaf_blocks.cpp).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "accel/bvh/node8.h"
#include "accel/common/cache_line_allocator.h"
#include "accel/core/primitives.h"
#include "accel/core/triangle4.h"

namespace ab {

/// Leaf blocks in leaf order. Not zeroed by resize(): pack_leaf_blocks writes every block in parallel.
using Triangle4Array = std::vector<Triangle4, UninitializedAllocator<Triangle4>>;
/// The ids of the blocks' lanes, written as the blocks are.
using BlockIdArray = std::vector<uint32_t, UninitializedAllocator<uint32_t>>;

/// The triangle blocks of a wide tree's leaves and the original id of every block lane.
struct Bvh8LeafBlocks {
  Triangle4Array blocks;  ///< four triangles per block, a leaf's blocks consecutive
  BlockIdArray ids;       ///< ids[4 * b + j]: id of lane j of block b (kInvalidId for padding)
};

/// Replaces each wide leaf's primitive range [child, child + count) of `order` by its blocks: lane child =
/// first block, count unchanged (the last block of a leaf is padded).
Bvh8LeafBlocks pack_leaf_blocks(Bvh8NodeArray& wide, std::span<const uint32_t> order,
                                const TrianglePrims& prims);

}  // namespace ab
