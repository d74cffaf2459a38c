// The traditional k-d tree build (Bentley 1975; the spatial-median k-d tree of the ray-tracing lectures):
// each node splits at the median of its primitives' centres along its longest axis (or the axes in turn),
// until a leaf holds at most leaf_size primitives, the depth limit is reached, or more than straddle_limit
// of them would straddle the plane (then splitting mostly duplicates them). Primitives are tracked by
// their perfect-split bounds inside the node box, and the partition is conservative: a primitive that
// touches the plane or comes within the insertion margin of it goes to both children.
// Two more rules bound the references on any input (large overlapping triangles, fans):
// - pbrt-v3's bad refines (Pharr, Jakob and Humphreys 2016, 4.4.2): a split is bad when its surface-area
//   cost estimate Ct + Ci (pL nL + pR nR) is not below the leaf's Ci n; the bad_refines-th bad split on a
//   path makes a leaf instead;
// - the reference budget (build_with_budget, refine_rules.h) as a safety net: at most ref_budget
//   references per primitive, the tree unchanged on any input whose tree stays under it.
#pragma once

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <vector>

#include "accel/common/conservative_insertion.h"
#include "accel/common/ref_frontier.h"
#include "accel/common/refine_rules.h"
#include "accel/kdtree/box_node.h"
#include "accel/kdtree/config.h"
#include "accel/kdtree/node.h"

namespace ab {

/// Builds median-split k-d trees over a primitive set P.
template <class P>
class KdMedianBuilder {
 public:
  /// Builder over prims with the tree's configuration and its resolved depth limit (> 0).
  KdMedianBuilder(const P& prims, const KdMedianConfig& config, int depth_limit)
      : prims_(prims), config_(config), depth_limit_(depth_limit) {}

  /// Builds the tree over the primitives ids (finite bounds) inside box into out.
  void build(const std::vector<uint32_t>& ids, const AABB& box, KdBuffer& out) const {
    margins_ = InsertionMargin(box);
    auto attempt = [&](RefLedger* ledger, RefBudget budget) {
      ledger_ = ledger;
      out = KdBuffer{};
      count_frontier_root(ledger, ids.size());
      build_node(make_box_root(prims_, ids, box), {0, 0, budget}, out);
    };
    budget_exhausted_ = build_with_budget(ids.size(), config_.ref_budget, depth_limit_, attempt);
    ledger_ = nullptr;
  }
  /// True when the tree was built with the reference budget (build_with_budget).
  bool budget_exhausted() const { return budget_exhausted_; }

 private:
  /// Where a node sits: its depth, the bad refines on its path, its reference budget.
  struct Path {
    int depth;
    int bad;
    RefBudget budget;
  };

  /// True when splitting a node (box, n primitives) into children (lbox, nl), (rbox, nr) should not be done.
  bool stop(const AABB& box, size_t n, const AABB& lbox, size_t nl, const AABB& rbox, size_t nr,
            Path& path) const {
    if (double(nl + nr) > double(n) * (1.0 + config_.straddle_limit)) return true;  // no longer pays
    const SahCosts& c = config_.costs;
    const double area = box.area();
    const double split =
        c.traversal +
        c.intersection *
            (area > 0.0 ? (lbox.area() * double(nl) + rbox.area() * double(nr)) / area : double(nl + nr));
    if (too_many_bad_refines(split >= c.intersection * double(n), config_.bad_refines, path.bad)) return true;
    return !path.budget.allows(nl + nr);
  }

  void build_node(KdBoxNode&& node, Path path, KdBuffer& out) const {
    if (ledger_ && ledger_->over()) return;  // an abandoned attempt
    const size_t n = node.ids.size();
    const int depth = path.depth;
    const int axis = config_.axis == KdAxisRule::kCycle ? depth % 3 : node.box.longest_axis();
    float split = 0.0f;
    if (n <= config_.leaf_size || depth >= depth_limit_ || !median_plane(node, axis, split))
      return make_leaf(node.ids, out);
    // Conservative: a primitive touching the plane or within the margin of it goes to both children.
    const float margin = margins_.of(node.box);
    auto side = [&](const AABB& cb) {
      const bool below = cb.lo[axis] <= split + margin, above = cb.hi[axis] >= split - margin;
      return uint8_t(below ? (above ? 3 : 1) : 2);
    };
    KdBoxNode left, right;
    partition_box_node(prims_, node, axis, split, margin, side, left, right);
    if (stop(node.box, n, left.box, left.ids.size(), right.box, right.ids.size(), path))
      return make_leaf(node.ids, out);
    node = KdBoxNode{};
    const size_t all = left.ids.size() + right.ids.size();
    count_frontier_split(ledger_, n, left.ids.size(), right.ids.size());
    const Path lp{depth + 1, path.bad, path.budget.share(left.ids.size(), all)};
    const Path rp{depth + 1, path.bad, path.budget.share(right.ids.size(), all)};
    const size_t self = out.nodes.size();
    out.nodes.push_back(KdNode::leaf(0, 0));
    build_kd_children(
        out, self, axis, split, n >= kParallelMin, [&](KdBuffer& b) { build_node(std::move(left), lp, b); },
        [&](KdBuffer& b) { build_node(std::move(right), rp, b); });
  }

  /// Median of the clipped centres along axis; false when it does not lie strictly inside the box.
  static bool median_plane(const KdBoxNode& node, int axis, float& split) {
    thread_local std::vector<float> c;
    c.resize(node.bounds.size());
    for (size_t i = 0; i < c.size(); ++i) c[i] = 0.5f * (node.bounds[i].lo[axis] + node.bounds[i].hi[axis]);
    auto mid = c.begin() + c.size() / 2;
    std::nth_element(c.begin(), mid, c.end());
    split = *mid;
    return split > node.box.lo[axis] && split < node.box.hi[axis];
  }

  /// Appends a leaf of ids (in the node's order, which is ascending: the root's, kept by every partition).
  void make_leaf(const std::vector<uint32_t>& ids, KdBuffer& out) const {
    out.nodes.push_back(out.make_leaf(ids));
  }

  /// Nodes at least this large build their children in parallel (1024: the two threads stay busy on
  /// unbalanced trees; the same tree for any thread count, subtrees appended in a fixed order).
  static constexpr size_t kParallelMin = 1024;
  const P& prims_;
  KdMedianConfig config_;
  int depth_limit_;
  mutable RefLedger* ledger_ = nullptr;  ///< the unbudgeted attempt's ledger (build_with_budget)
  mutable bool budget_exhausted_ = false;
  mutable InsertionMargin margins_;  ///< the tree's insertion margins (its root box's rule, set by build)
};

}  // namespace ab
