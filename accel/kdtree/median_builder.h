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
#include "accel/common/refine_rules.h"
#include "accel/kdtree/config.h"
#include "accel/kdtree/node.h"

namespace ab {

/// Builds median-split k-d trees over a primitive set P.
template <class P>
class KdMedianBuilder {
 public:
  /// A primitive in a node: its id and its bounds clipped to the node box.
  struct Ref {
    uint32_t id;  ///< primitive id
    AABB cb;      ///< its bounds clipped to the node box
  };

  /// Builder over prims with the tree's configuration and its resolved depth limit (> 0).
  KdMedianBuilder(const P& prims, const KdMedianConfig& config, int depth_limit)
      : prims_(prims), config_(config), depth_limit_(depth_limit) {}

  /// Builds the tree over the primitives ids (finite bounds) inside box into out.
  void build(const std::vector<uint32_t>& ids, const AABB& box, KdBuffer& out) const {
    auto attempt = [&](RefLedger* ledger, RefBudget budget) {
      ledger_ = ledger;
      out = KdBuffer{};
      std::vector<Ref> refs(ids.size());
      for (size_t i = 0; i < ids.size(); ++i) refs[i] = {ids[i], prims_.clipped_bounds(ids[i], box)};
      build_node(std::move(refs), box, {0, 0, budget}, out);
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

  void build_node(std::vector<Ref>&& refs, const AABB& box, Path path, KdBuffer& out) const {
    if (ledger_ && ledger_->over()) return;  // an abandoned attempt
    const size_t n = refs.size();
    const int depth = path.depth;
    int axis = config_.axis == KdAxisRule::kCycle ? depth % 3 : box.longest_axis();
    float split = 0.0f;
    if (n <= config_.leaf_size || depth >= depth_limit_ || !median_plane(refs, box, axis, split)) {
      make_leaf(refs, out);
      return;
    }
    std::vector<Ref> left, right;
    AABB lbox = box, rbox = box;
    lbox.hi[axis] = split;
    rbox.lo[axis] = split;
    partition(refs, axis, split, insertion_margin(box), lbox, rbox, left, right);
    if (stop(box, n, lbox, left.size(), rbox, right.size(), path)) {
      make_leaf(refs, out);
      return;
    }
    std::vector<Ref>().swap(refs);
    const size_t all = left.size() + right.size();
    if (ledger_) ledger_->add_children(all);
    const Path lp{depth + 1, path.bad, path.budget.share(left.size(), all)};
    const Path rp{depth + 1, path.bad, path.budget.share(right.size(), all)};
    const size_t self = out.nodes.size();
    out.nodes.push_back(KdNode::leaf(0, 0));
    if (n >= kParallelMin) {
      KdBuffer lb, rb;
      tbb::parallel_invoke([&] { build_node(std::move(left), lbox, lp, lb); },
                           [&] { build_node(std::move(right), rbox, rp, rb); });
      out.append(lb);
      out.nodes[self] = KdNode::interior(axis, split, uint32_t(out.nodes.size()));
      out.append(rb);
    } else {
      build_node(std::move(left), lbox, lp, out);
      out.nodes[self] = KdNode::interior(axis, split, uint32_t(out.nodes.size()));
      build_node(std::move(right), rbox, rp, out);
    }
  }

  /// Median of the clipped centres along axis; false when it does not lie strictly inside the box.
  static bool median_plane(const std::vector<Ref>& refs, const AABB& box, int axis, float& split) {
    std::vector<float> c(refs.size());
    for (size_t i = 0; i < refs.size(); ++i) c[i] = 0.5f * (refs[i].cb.lo[axis] + refs[i].cb.hi[axis]);
    auto mid = c.begin() + c.size() / 2;
    std::nth_element(c.begin(), mid, c.end());
    split = *mid;
    return split > box.lo[axis] && split < box.hi[axis];
  }

  void partition(const std::vector<Ref>& refs, int axis, float split, float margin, const AABB& lbox,
                 const AABB& rbox, std::vector<Ref>& left, std::vector<Ref>& right) const {
    for (const Ref& r : refs) {
      const bool to_left = r.cb.lo[axis] <= split + margin;
      const bool to_right = r.cb.hi[axis] >= split - margin;
      if (to_left && to_right) {
        left.push_back({r.id, clip_into_child(prims_, r.id, lbox, margin)});
        right.push_back({r.id, clip_into_child(prims_, r.id, rbox, margin)});
      } else if (to_left) {
        left.push_back(r);
      } else {
        right.push_back(r);
      }
    }
  }

  void make_leaf(const std::vector<Ref>& refs, KdBuffer& out) const {
    if (ledger_) ledger_->add_leaf(refs.size());
    std::vector<uint32_t> ids(refs.size());
    for (size_t i = 0; i < refs.size(); ++i) ids[i] = refs[i].id;
    std::sort(ids.begin(), ids.end());
    out.nodes.push_back(out.make_leaf(ids));
  }

  /// Nodes at least this large build their children in parallel.
  static constexpr size_t kParallelMin = 16384;
  const P& prims_;
  KdMedianConfig config_;
  int depth_limit_;
  mutable RefLedger* ledger_ = nullptr;  ///< the unbudgeted attempt's ledger (build_with_budget)
  mutable bool budget_exhausted_ = false;
};

}  // namespace ab
