// The O(N log N) SAH k-d tree build of Wald and Havran 2006, "On building fast kd-trees for ray tracing,
// and on doing that in O(N log N)": every node keeps, per axis, the list of its primitives' start, end and
// planar events, sorted; the best plane of all three axes is found by one linear sweep (sah_sweep.h), and
// the lists are split into the children's lists in linear time (primitives on one side keep their events
// in order; straddling ones are clipped to each child box, "perfect splits", and their few new events
// sorted and merged). Nodes above exact_max primitives (the top levels of a large mesh) choose their plane
// from bins instead and keep clipped boxes rather than events (sah_bins.h: Shevtsov, Soupikov and Kapustin
// 2007; Hunt, Mark and Stoll 2006), partitioned by the same classification and clipping in parallel; a
// node at exact_max or fewer gets its sorted events (Wald and Havran's lists, made per subtree) and the
// exact sweep from there. Cost model (SahCosts, sah.h): C = lambda (Ct + Ci (P_L N_L + P_R N_R)) with
// lambda = 1 - bonus when one side is empty; planar primitives are counted on the cheaper side; a node
// becomes a leaf when no plane beats Ci N, unless it holds more than max_leaf primitives: then it splits at
// its cheapest plane anyway when both children hold fewer than it. The SAH assumes rays that never stop
// (MacDonald and Booth 1990), so on large overlapping triangles, which every plane mostly duplicates, it
// prices every split above the leaf and makes one leaf of them all; a ray stops at its first hit, though,
// and smaller cells front to back let it stop after testing a few of them. The reference budget
// (build_with_budget, refine_rules.h) bounds those splits: at most ref_budget references per primitive,
// the tree unchanged on any input whose tree stays under it. The upper levels build in parallel on TBB; the
// tree is the same for any thread count (every subtree is built deterministically and spliced in a fixed
// order).
//
// Robustness without duplicating every primitive that touches a plane: the traversal widens the two
// halves of the ray interval around t_split (split_plane.h), so a hit on the plane itself (flat geometry
// lying in it, a vertex or edge touching it) is found on whichever side the primitive was placed; the
// straddling primitives are clipped into boxes grown by the insertion margin, so clipping rounding never
// drops a sliver.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "accel/common/conservative_insertion.h"
#include "accel/common/ref_frontier.h"
#include "accel/common/refine_rules.h"
#include "accel/common/sah.h"
#include "accel/kdtree/config.h"
#include "accel/kdtree/node.h"
#include "accel/kdtree/sah_bins.h"
#include "accel/kdtree/sah_sweep.h"

namespace ab {

/// Builds SAH k-d trees over a primitive set P.
template <class P>
class KdSahBuilder {
 public:
  /// Builder over prims with the tree's configuration and its resolved depth limit (> 0).
  KdSahBuilder(const P& prims, const KdSahConfig& config, int depth_limit)
      : prims_(prims), config_(config), costs_(config.costs), depth_limit_(depth_limit) {}

  /// Builds the tree over the primitives `ids` (finite bounds) inside `box` into out.
  void build(const std::vector<uint32_t>& ids, const AABB& box, KdBuffer& out) const {
    margins_ = InsertionMargin(box);
    auto attempt = [&](RefLedger* ledger, RefBudget budget) {
      ledger_ = ledger;
      out = KdBuffer{};
      count_frontier_root(ledger, ids.size());
      build_node(make_box_root(prims_, ids, box), {0, budget}, out);
    };
    budget_exhausted_ = build_with_budget(ids.size(), config_.ref_budget, depth_limit_, attempt);
    ledger_ = nullptr;
  }
  /// True when the tree was built with the reference budget (build_with_budget).
  bool budget_exhausted() const { return budget_exhausted_; }

 private:
  /// A node the exact sweep takes over: its events, sorted per axis (the lists Wald and Havran sort once
  /// at the root, made here per subtree). Sorted by KdEvent's total order: the same lists in any build.
  static KdEventNode to_events(KdBoxNode&& node) {
    KdEventNode e;
    e.box = node.box;
    e.ids = std::move(node.ids);
    for (auto& ev : e.events) ev.reserve(2 * e.ids.size());
    for (size_t i = 0; i < e.ids.size(); ++i) add_kd_events(node.bounds[i], uint32_t(i), e.events);
    std::vector<AABB>().swap(node.bounds);
    tbb::parallel_for(0, 3, [&](int a) { tbb::parallel_sort(e.events[a].begin(), e.events[a].end()); });
    return e;
  }

  /// Where a node sits: its depth and its reference budget.
  struct Path {
    int depth;
    RefBudget budget;
  };

  /// Appends a leaf of ids.
  void make_leaf(const std::vector<uint32_t>& ids, KdBuffer& out) const {
    out.nodes.push_back(out.make_leaf(ids));
  }

  KdSahChoice find_plane(const KdEventNode& node) const { return find_kd_sah_plane(costs_, node); }
  KdSahChoice find_plane(const KdBoxNode& node) const { return find_binned_kd_plane(costs_, node); }

  /// The plane a node of n primitives splits at, or null for a leaf: the cheapest plane when it beats the
  /// leaf, else (more than max_leaf primitives) the cheapest one with progress.
  const KdSahPlane* chosen_plane(const KdSahChoice& choice, size_t n, bool& forced) const {
    forced = choice.best.axis >= 0 && choice.best.cost >= costs_.leaf(n);  // max_leaf's split
    if (choice.best.axis < 0 || (forced && (config_.max_leaf == 0 || n <= config_.max_leaf))) return nullptr;
    const KdSahPlane& plane = forced ? choice.progress : choice.best;
    return plane.axis < 0 ? nullptr : &plane;
  }

  /// Builds a node (KdBoxNode: binned planes, handed to the exact sweep at exact_max primitives or fewer;
  /// KdEventNode: the exact sweep).
  template <class Node>
  void build_node(Node node, Path path, KdBuffer& out) const {
    if (ledger_ && ledger_->over()) return;  // an abandoned attempt
    const size_t n = node.ids.size();
    if constexpr (std::is_same_v<Node, KdBoxNode>)
      if (n <= config_.exact_max) return build_node(to_events(std::move(node)), path, out);
    KdSahChoice choice;
    if (n > 0 && path.depth < depth_limit_) choice = find_plane(node);
    bool forced = false;
    const KdSahPlane* plane = chosen_plane(choice, n, forced);
    if (!plane) return make_leaf(node.ids, out);
    const int axis = plane->axis;
    const float split = plane->pos;
    Node left, right;
    partition(std::move(node), axis, split, plane->planar_left, left, right);
    const size_t nl = left.ids.size(), nr = right.ids.size();
    if ((nl == n && nr == n) || (forced && std::max(nl, nr) == n) || !path.budget.allows(nl + nr)) {
      std::vector<uint32_t> ids = std::move(left.ids);  // all n when nl == n
      if (nl != n) ids = merged_ids(ids, right.ids);
      return make_leaf(ids, out);
    }
    count_frontier_split(ledger_, n, nl, nr);
    const Path lp{path.depth + 1, path.budget.share(nl, nl + nr)};
    const Path rp{path.depth + 1, path.budget.share(nr, nl + nr)};
    const size_t self = out.nodes.size();
    out.nodes.push_back(KdNode::leaf(0, 0));
    build_kd_children(
        out, self, axis, split, n >= kParallelMin, [&](KdBuffer& b) { build_node(std::move(left), lp, b); },
        [&](KdBuffer& b) { build_node(std::move(right), rp, b); });
  }

  /// The node's primitives from its two children's lists (each in the node's order): sorted, once each.
  static std::vector<uint32_t> merged_ids(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    std::vector<uint32_t> out(a.size() + b.size());
    std::merge(a.begin(), a.end(), b.begin(), b.end(), out.begin());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  /// Splits a large node at `split` on axis a by kd_side on the clipped boxes, straddlers clipped into
  /// each child (the exact partition's rules, so the subtree below is the one the exact build of this
  /// node would make; partition_box_node).
  void partition(KdBoxNode&& node, int a, float split, bool planar_left, KdBoxNode& left,
                 KdBoxNode& right) const {
    partition_box_node(
        prims_, node, a, split, margins_.of(node.box),
        [&](const AABB& cb) { return kd_side(cb.lo[a], cb.hi[a], split, planar_left); }, left, right);
    std::vector<uint32_t>().swap(node.ids);
    std::vector<AABB>().swap(node.bounds);
  }

  /// Splits node's primitives and events at `split` on axis a into left and right (linear time). The
  /// per-primitive scratch is kept per thread (no allocation per node).
  void partition(KdEventNode&& node, int a, float split, bool planar_left, KdEventNode& left,
                 KdEventNode& right) const {
    const size_t n = node.ids.size();
    const float margin = margins_.of(node.box);
    child_boxes(node.box, a, split, left.box, right.box);
    // Side of each primitive (bit 0 left, bit 1 right), Wald and Havran's classification: ending at or
    // before the plane is left only, starting at or after it right only, planar in it on the chosen side.
    thread_local std::vector<uint8_t> side;
    thread_local std::vector<uint32_t> to_left, to_right;
    side.assign(n, 3);
    to_left.resize(n);
    to_right.resize(n);
    for (const KdEvent& e : node.events[a]) {
      const uint32_t t = e.local();
      if (e.type() == KdEvent::kEnd && e.pos <= split)
        side[t] = 1;
      else if (e.type() == KdEvent::kStart && e.pos >= split)
        side[t] = 2;
      else if (e.type() == KdEvent::kPlanar)
        side[t] = e.pos < split ? 1 : e.pos > split ? 2 : planar_left ? 1 : 2;
    }
    size_t nl = 0, nr = 0, both = 0;
    for (size_t t = 0; t < n; ++t) {
      nl += side[t] & 1;
      nr += side[t] >> 1;
      both += side[t] == 3;
    }
    left.ids.resize(nl);
    right.ids.resize(nr);
    for (size_t t = 0, l = 0, r = 0; t < n; ++t) {
      if (side[t] & 1) left.ids[to_left[t] = uint32_t(l++)] = node.ids[t];
      if (side[t] & 2) right.ids[to_right[t] = uint32_t(r++)] = node.ids[t];
    }
    for (int k = 0; k < 3; ++k) {
      const size_t m = node.events[k].size();
      left.events[k].reserve(m * (nl - both) / n + 2 * both + 8);
      right.events[k].reserve(m * (nr - both) / n + 2 * both + 8);
      split_events(node.events[k], side, to_left, to_right, left.events[k], right.events[k]);
      std::vector<KdEvent>().swap(node.events[k]);
    }
    if (both == 0) return;
    add_straddlers(node.ids, side, to_left, margin, left);
    add_straddlers(node.ids, side, to_right, margin, right);
  }

  /// Events of one-sided primitives keep their order in their side's list.
  static void split_events(const std::vector<KdEvent>& ev, const std::vector<uint8_t>& side,
                           const std::vector<uint32_t>& to_left, const std::vector<uint32_t>& to_right,
                           std::vector<KdEvent>& left, std::vector<KdEvent>& right) {
    for (const KdEvent& e : ev) {
      const uint32_t t = e.local();
      if (side[t] == 1)
        left.push_back({e.pos, (to_left[t] << 2) | e.type()});
      else if (side[t] == 2)
        right.push_back({e.pos, (to_right[t] << 2) | e.type()});
    }
  }

  /// Merges the sorted `extra` into the sorted `ev` in place, from the back (std::merge's result: the keys
  /// are distinct, so KdEvent's order has no ties).
  static void merge_into(std::vector<KdEvent>& ev, const std::vector<KdEvent>& extra) {
    size_t i = ev.size(), j = extra.size(), k = i + j;
    ev.resize(k);
    while (j > 0) ev[--k] = (i > 0 && extra[j - 1] < ev[i - 1]) ? ev[--i] : extra[--j];
  }

  /// Clips the primitives on both sides into child (perfect splits), sorts their events and merges them in.
  void add_straddlers(const std::vector<uint32_t>& ids, const std::vector<uint8_t>& side,
                      const std::vector<uint32_t>& to_child, float margin, KdEventNode& child) const {
    thread_local std::array<std::vector<KdEvent>, 3> extra;
    for (auto& e : extra) e.clear();
    for (size_t t = 0; t < ids.size(); ++t) {
      if (side[t] != 3) continue;
      add_kd_events(clip_into_child(prims_, ids[t], child.box, margin), to_child[t], extra);
    }
    for (int k = 0; k < 3; ++k) {
      if (extra[k].empty()) continue;
      std::sort(extra[k].begin(), extra[k].end());
      merge_into(child.events[k], extra[k]);
    }
  }

  /// Nodes at least this large build their children in parallel (each into its own buffer, appended in a
  /// fixed order: the same tree for any thread count). 1024, not 16384: at 20k triangles 16384 left only
  /// the root's two subtrees to the threads, and on unbalanced trees (a fan) one thread did most of it.
  static constexpr size_t kParallelMin = 1024;
  const P& prims_;
  KdSahConfig config_;
  SahCosts costs_;
  int depth_limit_;
  mutable RefLedger* ledger_ = nullptr;  ///< the unbudgeted attempt's ledger (build_with_budget)
  mutable bool budget_exhausted_ = false;
  mutable InsertionMargin margins_;  ///< the tree's insertion margins (its root box's rule, set by build)
};

}  // namespace ab
