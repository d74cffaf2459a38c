// The first attempt's ledger counted by the frontier (build_with_budget, refine_rules.h): the references of
// the root and of each split's children beyond their parent's, instead of those of the leaves made so far.
// The same sum once the tree is done (every node either becomes a leaf of its references or splits), but
// it only grows, and passes ref_budget x N as soon as the splits made so far have copied that many: a tree
// over the budget is abandoned after its first few duplicating levels (large overlapping triangles: every
// split copies most of them) instead of after ref_budget x N references of finished leaves. Whether it
// passes is still a property of the tree alone. The k-d trees and the bsp count their first attempts this
// way.
#pragma once

#include <cstddef>

#include "accel/common/refine_rules.h"

namespace ab {

/// Counts the root's n references into the first attempt's ledger (none: the budgeted attempt).
inline void count_frontier_root(RefLedger* ledger, size_t n) {
  if (ledger) ledger->add_leaf(n);
}

/// Counts the split of a node of n references into children of nl and nr references.
inline void count_frontier_split(RefLedger* ledger, size_t n, size_t nl, size_t nr) {
  if (!ledger) return;
  ledger->add_children(nl + nr);
  ledger->add_leaf(nl + nr > n ? nl + nr - n : 0);
}

}  // namespace ab
