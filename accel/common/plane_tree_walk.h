// The front-to-back walk of a binary tree of split planes (the k-d trees' axis planes, the BSP tree's
// arbitrary planes), written once: Havran's stack traversal (Havran 2000, "Heuristic ray shooting
// algorithms", TA_B rec) in the tight form of pbrt's KdTreeAggregate, with the one plane step
// (split_plane.h) at every interior node and the one stack (traversal_stack.h).
#pragma once

#include <cstdint>

#include "accel/common/split_plane.h"
#include "accel/common/traversal_stack.h"
#include "accel/core/stats.h"

namespace ab {

/// A child waiting on the walk's stack: its node and the ray interval that reaches it.
struct PlaneTreeEntry {
  uint32_t node;  ///< the child
  float t0, t1;   ///< the ray interval inside it
  /// The entry distance (pruned when beyond the best hit).
  float entry() const { return t0; }
};

/// Stack capacity of the walk: one entry per interior node on a path whose children are both visited, so
/// the trees' depth limits (at most 100 levels that can push) bound it.
inline constexpr int kPlaneTreeStackSize = 128;

/// Walks a binary plane tree front to back over the ray interval [t0, t1] (the root box's, already clipped).
/// Node (8 bytes, depth-first layout) provides is_leaf(), first() and count() (leaves), above(),
/// below_empty() and above_empty() (interior nodes): the below child of node i is node i + 1 unless it is
/// flagged empty. cross(node) is the ray's PlaneCrossing of an interior node's plane; the first child
/// continues and the second, when the interval reaches it, goes on the stack. leaf(first, count) returns
/// true to stop (any hit); a stacked child is popped only when its entry is not beyond best_t().
template <bool kCount, class Node, class Cross, class Leaf, class BestT>
[[gnu::always_inline]] inline bool walk_plane_tree(const Node* nodes, float t0, float t1, RayCounters& c,
                                                   Cross&& cross, Leaf&& leaf, BestT&& best_t) {
  TraversalStack<PlaneTreeEntry, kPlaneTreeStackSize> stack;
  uint32_t idx = 0;
  for (;;) {
    Node n = nodes[idx];
    while (!n.is_leaf()) {  // down to a leaf, stacking the second children the interval reaches
      if constexpr (kCount) ++c.nodes;
      const PlaneCrossing x = cross(n);
      const uint32_t below = idx + 1, above = n.above();
      const uint32_t first = x.below_first ? below : above;
      const uint32_t second = x.below_first ? above : below;
      const bool first_empty = x.below_first ? n.below_empty() : n.above_empty();
      const bool second_empty = x.below_first ? n.above_empty() : n.below_empty();
      const bool visit_first = x.reaches_first(t0) && !first_empty;
      const bool visit_second = x.reaches_second(t1) && !second_empty;
      if (visit_first) {
        if (visit_second) stack.push({second, x.second_entry(t0), t1});
        t1 = x.first_exit(t1);
        idx = first;
      } else if (visit_second) {
        t0 = x.second_entry(t0);
        idx = second;
      } else {
        break;  // only an empty child lies in the interval
      }
      n = nodes[idx];
    }
    if (n.is_leaf()) {
      if constexpr (kCount) {
        ++c.nodes;
        ++c.leaves;
      }
      if (n.count() && leaf(n.first(), n.count())) return true;
    }
    PlaneTreeEntry next;
    if (!stack.pop(best_t(), next)) return false;
    idx = next.node;
    t0 = next.t0;
    t1 = next.t1;
  }
}

}  // namespace ab
