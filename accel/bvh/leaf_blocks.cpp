#include "accel/bvh/leaf_blocks.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <type_traits>

#include "accel/bvh/leaf_fill.h"
#include "accel/common/huge_pages.h"

namespace ab {

static_assert(std::is_trivially_default_constructible_v<Triangle4>);

namespace {

/// Blocks of four that a leaf of n primitives takes.
uint32_t blocks_of(uint32_t n) {
  return (n + 3) / 4;
}

/// Packs the leaves of one node into the blocks from `first` on (and their ids), rewriting the lanes; leaves
/// of two blocks first fill the node's free lanes (fill_free_lanes), which takes as many blocks.
void pack_node(Bvh8Node& node, uint32_t first, std::span<const uint32_t> order, const TrianglePrims& prims,
               Bvh8LeafBlocks& out) {
  NodeLaneIds lanes;
  fill_free_lanes(node, order, prims, lanes);
  for (int k = 0; k < Bvh8Node::kWidth; ++k) {
    if (node.count[k] == 0) continue;
    const uint32_t* ids = lanes.lane[k];
    const uint32_t n = node.count[k];
    node.child[k] = first;
    for (uint32_t s = 0; s < n; s += 4, ++first) {
      Triangle quad[4] = {};  // only the first m are read; zeroed so no lane is uninitialized
      const uint32_t m = std::min(4u, n - s);
      for (uint32_t j = 0; j < 4; ++j) {
        if (j < m) quad[j] = prims.triangle(ids[s + j]);
        out.ids[4 * size_t(first) + j] = j < m ? ids[s + j] : kInvalidId;
      }
      out.blocks[first] = Triangle4::pack(std::span<const Triangle>(quad, m));
    }
  }
}

/// Prefetches the triangles of the leaves of `node` (not yet packed): the packing gathers them by id from
/// the whole triangle array, which for an unordered mesh is a cache miss per triangle.
void prefetch_leaves(const Bvh8Node& node, std::span<const uint32_t> order, const TrianglePrims& prims) {
  for (int k = 0; k < Bvh8Node::kWidth; ++k)
    for (uint32_t j = 0; j < node.count[k]; ++j)
      __builtin_prefetch(&prims.triangle(order[node.child[k] + j]));
}

}  // namespace

// The blocks are laid out node by node in lane order; each node's first block comes from a prefix sum, so
// the nodes are packed in parallel into preallocated arrays (the same bytes as a serial pass). The arrays
// are not zeroed by their resize (UninitializedAllocator), so their pages are first touched, faulted and
// zeroed by the kernel, in the parallel packing instead of on one thread. Each node's triangles are
// prefetched while the node before it is packed.
Bvh8LeafBlocks pack_leaf_blocks(Bvh8NodeArray& wide, std::span<const uint32_t> order,
                                const TrianglePrims& prims) {
  std::vector<uint32_t> first(wide.size() + 1, 0);
  for (size_t i = 0; i < wide.size(); ++i) {
    uint32_t n = 0;
    for (int k = 0; k < Bvh8Node::kWidth; ++k) n += blocks_of(wide[i].count[k]);
    first[i + 1] = first[i] + n;
  }
  Bvh8LeafBlocks out;
  out.blocks.resize(first.back());
  out.ids.resize(4 * size_t(first.back()));
  tbb::parallel_for(tbb::blocked_range<size_t>(0, wide.size(), 1024),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        if (i + 1 < r.end()) prefetch_leaves(wide[i + 1], order, prims);
                        pack_node(wide[i], first[i], order, prims, out);
                      }
                    });
  return out;
}

}  // namespace ab
