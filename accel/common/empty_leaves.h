// Empty leaves as flags: a space-partitioning tree cuts off empty space, and an empty leaf costs a node,
// a visit and a stack entry for nothing. After the build, the parents of empty leaves flag them instead
// (the k-d trees and the BSP tree), so the traversal never reaches them.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "accel/common/cache_line_allocator.h"
#include "accel/core/error.h"

namespace ab {

/// Removes the empty leaves of a depth-first tree (all but an empty root): their parents flag them instead.
/// Node provides is_leaf(), count(), above() and relinked(above, below_empty, above_empty) (a copy of an
/// interior node with a new above index and flags), and kMaxIndex. Throws InputError when the remaining
/// nodes do not fit the node's index field. Large trees are done in chunks in parallel: each chunk's kept
/// nodes are counted, their places follow from the counts before it, then each chunk writes its nodes (the
/// same nodes as one pass; at 10M triangles one pass over 31M nodes took a second on one core).
template <class Node>
void drop_empty_leaves(std::vector<Node>& nodes) {
  const size_t n = nodes.size(), chunk = size_t(1) << 16, chunks = (n + chunk - 1) / chunk;
  auto empty = [&](size_t i) { return i != 0 && nodes[i].is_leaf() && nodes[i].count() == 0; };
  auto each_chunk = [&](auto&& f) {
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) { f(c * chunk, std::min(n, (c + 1) * chunk)); });
  };
  std::vector<uint32_t, UninitializedAllocator<uint32_t>> remap(n);  // each written before it is read
  std::vector<size_t> at(chunks + 1, 0);                             // kept nodes before each chunk
  each_chunk([&](size_t first, size_t end) {
    size_t kept = 0;
    for (size_t i = first; i < end; ++i) kept += !empty(i);
    at[first / chunk + 1] = kept;
  });
  for (size_t c = 0; c < chunks; ++c) at[c + 1] += at[c];
  if (at[chunks] > Node::kMaxIndex)
    throw InputError("tree of more nodes than its node format can index (mesh too large)");
  each_chunk([&](size_t first, size_t end) {
    size_t kept = at[first / chunk];
    for (size_t i = first; i < end; ++i) {
      remap[i] = uint32_t(kept);
      kept += !empty(i);
    }
  });
  std::vector<Node> out;
  if (n > 0) out.assign(at[chunks], nodes[0]);  // every place is written below
  each_chunk([&](size_t first, size_t end) {
    for (size_t i = first; i < end; ++i) {
      const Node& nd = nodes[i];
      if (empty(i)) continue;
      if (nd.is_leaf()) {
        out[remap[i]] = nd;
        continue;
      }
      const bool below_empty = empty(i + 1);
      const bool above_empty = empty(nd.above()) && !below_empty;  // a split always keeps one side
      out[remap[i]] = nd.relinked(above_empty ? 0 : remap[nd.above()], below_empty, above_empty);
    }
  });
  nodes.swap(out);
}

}  // namespace ab
