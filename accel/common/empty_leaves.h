// Empty leaves as flags: a space-partitioning tree cuts off empty space, and an empty leaf costs a node,
// a visit and a stack entry for nothing. After the build, the parents of empty leaves flag them instead
// (the k-d trees and the BSP tree), so the traversal never reaches them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "accel/core/error.h"

namespace ab {

/// Removes the empty leaves of a depth-first tree (all but an empty root): their parents flag them instead.
/// Node provides is_leaf(), count(), above() and relinked(above, below_empty, above_empty) (a copy of an
/// interior node with a new above index and flags), and kMaxIndex. Throws InputError when the remaining
/// nodes do not fit the node's index field.
template <class Node>
void drop_empty_leaves(std::vector<Node>& nodes) {
  const size_t n = nodes.size();
  auto empty = [&](size_t i) { return i != 0 && nodes[i].is_leaf() && nodes[i].count() == 0; };
  std::vector<uint32_t> remap(n);
  size_t kept = 0;
  for (size_t i = 0; i < n; ++i) {
    remap[i] = uint32_t(kept);
    kept += !empty(i);
  }
  if (kept > Node::kMaxIndex)
    throw InputError("tree of more nodes than its node format can index (mesh too large)");
  std::vector<Node> out;
  out.reserve(kept);
  for (size_t i = 0; i < n; ++i) {
    const Node& nd = nodes[i];
    if (empty(i)) continue;
    if (nd.is_leaf()) {
      out.push_back(nd);
      continue;
    }
    const bool below_empty = empty(i + 1);
    const bool above_empty = empty(nd.above()) && !below_empty;  // a split always keeps one side
    out.push_back(nd.relinked(above_empty ? 0 : remap[nd.above()], below_empty, above_empty));
  }
  nodes.swap(out);
}

}  // namespace ab
