// Filling a wide node's free lanes by splitting its two-block leaves, as Embree's wide builder fills a node
// (Wald, Woop, Benthin, Johnson and Ernst 2014, "Embree: a kernel framework for efficient CPU ray tracing":
// the top-down build splits the node's largest child until it has N children, leaves included while they
// hold more than one block). A binary SAH build keeps a leaf of five to eight triangles whenever a split
// would cost a node test more than it saves, but in the 8-wide tree a split into lanes of the same node
// costs no node test: the eight boxes are tested at once. So a leaf of two blocks in a node with a free
// lane becomes two leaves of one block each, and a ray that enters only one of them tests one block
// instead of two. The blocks a leaf takes do not change (two either way), nor do the hits (the same
// triangles in boxes that still hold them).
#pragma once

#include <cstdint>
#include <span>

#include "accel/bvh/node8.h"
#include "accel/core/primitives.h"

namespace ab {

/// The triangle ids of each lane of a wide node in the order they are packed: lane k's count
/// (Bvh8Node::count) ids from lane[k].
struct NodeLaneIds {
  const uint32_t* lane[Bvh8Node::kWidth] = {};        ///< each leaf lane's ids (into the order or own)
  uint32_t own[Bvh8Node::kWidth * Bvh8Node::kWidth];  ///< reordered ids of the leaves split here
};

/// Splits node's leaves of five to eight triangles (ids order[child, child + count)) into two lanes of at
/// most four while the node has unused lanes, the leaf of the largest box first (Embree's rule), each at
/// the sweep over sorted centroids that minimizes the two boxes' summed area; the new boxes are the
/// triangles' bounds clipped to the leaf's box. Fills ids with every leaf lane's ids in packing order.
void fill_free_lanes(Bvh8Node& node, std::span<const uint32_t> order, const TrianglePrims& prims,
                     NodeLaneIds& ids);

}  // namespace ab
