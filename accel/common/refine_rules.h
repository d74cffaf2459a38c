// Termination rules shared by the space-partitioning trees (k-d trees, octree, BSP tree): the reference
// budget, a safety net that bounds the references in the leaves whatever the input, and the bad-refine count.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace ab {

/// References a subtree may hold in its leaves, for the budgeted build (build_with_budget's second attempt).
/// The root gets ref_budget x its primitive count; a node splits only when its children's references fit
/// in its budget, and the children share the budget in proportion to their references, so every child fits
/// and the leaves of the whole tree hold at most the root's budget. It depends only on the node, not on the
/// build order, so the tree is the same for any thread count. Its flaw, why it is only the fallback: a
/// node's share is the root's ratio divided by the product of the duplication factors on its path, so deep
/// paths through mild duplication run out of it on ordinary inputs.
struct RefBudget {
  double refs = std::numeric_limits<double>::infinity();  ///< references this subtree may hold

  /// True when children holding `children_refs` references in all fit.
  bool allows(size_t children_refs) const { return double(children_refs) <= refs; }
  /// The share of a child holding `child_refs` of the `children_refs` references.
  RefBudget share(size_t child_refs, size_t children_refs) const {
    if (refs == std::numeric_limits<double>::infinity()) return *this;  // unbudgeted
    return {refs * double(child_refs) / double(children_refs)};
  }
};

/// Running sums of the first, unbudgeted attempt of build_with_budget: the references in the leaves made so
/// far, and the references of every node made so far (the work). The attempt is abandoned as soon as either
/// passes its cap: the leaves' cap is ref_budget x N, the nodes' cap that times (depth limit + 2), which a
/// tree of ref_budget x N leaf references whose every level holds at most its leaves' references never
/// reaches. Both sums only grow and reach the same final values in any build order, so whether the attempt
/// is abandoned is a property of the unbudgeted tree alone, never of the thread count.
class RefLedger {
 public:
  /// Caps for n primitives, ref_budget references per primitive and a depth limit.
  RefLedger(size_t n, double ref_budget, int depth_limit)
      : leaf_cap_(ref_budget * double(n)), node_cap_(leaf_cap_ * double(depth_limit + 2)) {}

  /// Counts a leaf of `refs` references.
  void add_leaf(size_t refs) { add(leaf_refs_, refs, leaf_cap_); }
  /// Counts the children (`refs` references in all) of a node that splits.
  void add_children(size_t refs) { add(node_refs_, refs, node_cap_); }
  /// True once a cap was passed: the attempt is abandoned (the builders return at once).
  bool over() const { return over_.load(std::memory_order_relaxed); }

 private:
  void add(std::atomic<uint64_t>& sum, size_t refs, double cap) {
    if (double(sum.fetch_add(refs, std::memory_order_relaxed) + refs) > cap)
      over_.store(true, std::memory_order_relaxed);
  }
  double leaf_cap_, node_cap_;
  std::atomic<uint64_t> leaf_refs_{0}, node_refs_{0};
  std::atomic<bool> over_{false};
};

/// The reference budget as a safety net that ordinary inputs never reach. `attempt(ledger, budget)` builds
/// the whole tree (starting from an empty output): first unbudgeted with a ledger, so the tree is exactly
/// what the other termination rules give; only when that tree would hold more than ref_budget x N
/// references in its leaves (or its nodes more than the ledger's work cap) is it abandoned and built again
/// with the proportional RefBudget and no ledger. Bound: the leaves hold at most ref_budget x N references
/// on any input (the first tree stayed under the ledger's cap, or RefBudget's conservation bounds the
/// second), and the build does at most the ledger's cap of node references before the second attempt. The
/// same tree for any thread count (RefLedger, RefBudget). Returns true when the budget was needed.
template <class Attempt>
bool build_with_budget(size_t n, double ref_budget, int depth_limit, Attempt&& attempt) {
  RefLedger ledger(n, ref_budget, depth_limit);
  attempt(&ledger, RefBudget{});
  if (!ledger.over()) return false;
  attempt(nullptr, RefBudget{ref_budget * double(n)});
  return true;
}

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
