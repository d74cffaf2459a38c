// Termination rules shared by the space-partitioning trees (k-d trees, octree): the reference budget, a
// safety net that bounds the references in the leaves whatever the input, and the bad-refine count.
#pragma once

#include <atomic>
#include <cstddef>

namespace ab {

/// References a subtree may hold in its leaves. The root gets ref_budget x its primitive count; a node
/// splits only when its children's references fit in its budget, and the children share the budget in
/// proportion to their references, so every child fits and the leaves of the whole tree hold at most the
/// root's budget. It depends only on the node, not on the build order, so the tree is the same for any
/// thread count.
struct RefBudget {
  double refs = 0.0;  ///< references this subtree may hold

  /// True when children holding `children_refs` references in all fit.
  bool allows(size_t children_refs) const { return double(children_refs) <= refs; }
  /// The share of a child holding `child_refs` of the `children_refs` references.
  RefBudget share(size_t child_refs, size_t children_refs) const {
    return {refs * double(child_refs) / double(children_refs)};
  }
};

/// Set when some node became a leaf because its split did not fit the budget (reported as
/// extra.budget_exhausted).
using BudgetFlag = std::atomic<bool>;

/// pbrt-v3's bad-refine rule (Pharr, Jakob and Humphreys 2016, section 4.4.2, KdTreeAccel::buildTree): a
/// split whose estimated cost is not below the leaf's is a bad refine; it is allowed, since a later split
/// may pay for it, but a node whose split would be the `limit`-th bad refine on its path from the root
/// becomes a leaf. limit 0 disables the rule. Returns true when the node must be a leaf; counts `bad`.
inline bool too_many_bad_refines(bool bad_split, int limit, int& bad) {
  if (!bad_split) return false;
  ++bad;
  return limit > 0 && bad >= limit;
}

}  // namespace ab
