// The O(N log N) SAH k-d tree build of Wald and Havran 2006, "On building fast kd-trees for ray tracing,
// and on doing that in O(N log N)": every node keeps, per axis, the list of its primitives' start, end and
// planar events sorted once at the root; the best plane of all three axes is found by one linear sweep,
// and the lists are split into the children's lists in linear time (primitives on one side keep their
// events in order; straddling ones are clipped to each child box, "perfect splits", and their few new
// events sorted and merged). Cost model (SahCosts, sah.h): C = lambda (Ct + Ci (P_L N_L + P_R N_R)) with
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

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "accel/common/conservative_insertion.h"
#include "accel/common/refine_rules.h"
#include "accel/common/sah.h"
#include "accel/kdtree/config.h"
#include "accel/kdtree/node.h"

namespace ab {

/// A sweep event: position along one axis and (primitive's index in its node << 2 | type).
struct KdEvent {
  float pos;     ///< position along the axis
  uint32_t key;  ///< local index << 2 | type

  /// Event types, in the order the sweep needs at one position: ends, planars, starts.
  enum Type : uint32_t { kEnd = 0, kPlanar = 1, kStart = 2 };
  /// Index of the primitive in its node.
  uint32_t local() const { return key >> 2; }
  /// The event's type.
  uint32_t type() const { return key & 3u; }
  /// Total order: position, then type, then primitive (so any sort gives the same list).
  bool operator<(const KdEvent& o) const {
    if (pos != o.pos) return pos < o.pos;
    const uint32_t ta = type(), tb = o.type();
    return ta != tb ? ta < tb : key < o.key;
  }
};

/// A node under construction: box, primitive ids and the sorted events of each axis.
struct KdEventNode {
  AABB box;                                    ///< the node's box
  std::vector<uint32_t> ids;                   ///< its primitives
  std::array<std::vector<KdEvent>, 3> events;  ///< per axis, sorted
};

/// Appends the events of a primitive with clipped bounds cb as local index `local`.
inline void add_kd_events(const AABB& cb, uint32_t local, std::array<std::vector<KdEvent>, 3>& ev) {
  for (int a = 0; a < 3; ++a) {
    if (cb.lo[a] == cb.hi[a]) {
      ev[a].push_back({cb.lo[a], (local << 2) | KdEvent::kPlanar});
    } else {
      ev[a].push_back({cb.lo[a], (local << 2) | KdEvent::kStart});
      ev[a].push_back({cb.hi[a], (local << 2) | KdEvent::kEnd});
    }
  }
}

/// Result of the sweep.
struct KdSahPlane {
  int axis = -1;                     ///< -1: no plane inside the box
  float pos = 0.0f;                  ///< plane position
  float cost = kInf;                 ///< its SAH cost
  bool planar_left = true;           ///< planar primitives at pos are counted on the left
  uint32_t n_left = 0, n_right = 0;  ///< primitives on each side
};

/// Area terms of the children of a node box along one axis, so that each plane costs a few flops.
struct KdAxisAreas {
  float lo, hi, cap, side, inv_area;  ///< child area = (cap + side * length) * inv_area

  /// Terms of box along axis a.
  KdAxisAreas(const AABB& box, int a) : lo(box.lo[a]), hi(box.hi[a]) {
    const vec3 e = box.extent();
    const float e1 = e[(a + 1) % 3], e2 = e[(a + 2) % 3];
    cap = 2.0f * e1 * e2;
    side = 2.0f * (e1 + e2);
    inv_area = 1.0f / box.area();
  }
};

/// The cheapest plane of a node, and the cheapest one that leaves fewer than all n primitives on each side
/// (the plane of a max_leaf split, which must make progress).
struct KdSahChoice {
  KdSahPlane best;      ///< cheapest plane
  KdSahPlane progress;  ///< cheapest plane with both sides smaller than the node
};

/// Keeps plane (a, pos, cost c, planar side, counts) in best when cheaper.
inline void keep_cheaper(KdSahPlane& best, int a, float pos, float c, bool planar_left, uint32_t nl,
                         uint32_t nr) {
  if (c < best.cost) best = {a, pos, c, planar_left, nl, nr};
}

/// Evaluates plane `pos` on axis a with the paper's counts, both placements of planar primitives. The
/// areas are relative to the node's (the probabilities P_L, P_R), so the cost model is called with a
/// parent area of 1.
inline void evaluate_kd_plane(const SahCosts& costs, const KdAxisAreas& ar, int a, float pos, uint32_t nl,
                              uint32_t np, uint32_t nr, uint32_t n, KdSahChoice& choice) {
  const float pl = (ar.cap + ar.side * (pos - ar.lo)) * ar.inv_area;
  const float pr = (ar.cap + ar.side * (ar.hi - pos)) * ar.inv_area;
  const float cl = costs.split(1.0f, pl, nl + np, pr, nr);
  const float cr = np ? costs.split(1.0f, pl, nl, pr, nr + np) : cl;
  keep_cheaper(choice.best, a, pos, std::min(cl, cr), cl <= cr, cl <= cr ? nl + np : nl,
               cl <= cr ? nr : nr + np);
  if (nl + np < n && nr < n) keep_cheaper(choice.progress, a, pos, cl, true, nl + np, nr);
  if (np && nl < n && nr + np < n) keep_cheaper(choice.progress, a, pos, cr, false, nl, nr + np);
}

/// Finds the cheapest plane strictly inside the node box by one sweep per axis (Wald and Havran 2006,
/// algorithm 4).
inline KdSahChoice find_kd_sah_plane(const SahCosts& costs, const KdEventNode& node) {
  KdSahChoice best;
  if (!(node.box.area() > 0.0f)) return best;
  const uint32_t n = uint32_t(node.ids.size());
  for (int a = 0; a < 3; ++a) {
    const std::vector<KdEvent>& ev = node.events[a];
    const KdAxisAreas ar(node.box, a);
    uint32_t nl = 0, nr = n;
    for (size_t i = 0; i < ev.size();) {
      const float p = ev[i].pos;
      uint32_t ends = 0, planars = 0, starts = 0;
      for (; i < ev.size() && ev[i].pos == p && ev[i].type() == KdEvent::kEnd; ++i) ++ends;
      for (; i < ev.size() && ev[i].pos == p && ev[i].type() == KdEvent::kPlanar; ++i) ++planars;
      for (; i < ev.size() && ev[i].pos == p && ev[i].type() == KdEvent::kStart; ++i) ++starts;
      nr -= planars + ends;
      if (p > node.box.lo[a] && p < node.box.hi[a])
        evaluate_kd_plane(costs, ar, a, p, nl, planars, nr, n, best);
      nl += starts + planars;
    }
  }
  return best;
}

/// Builds SAH k-d trees over a primitive set P.
template <class P>
class KdSahBuilder {
 public:
  /// Builder over prims with the tree's configuration and its resolved depth limit (> 0).
  KdSahBuilder(const P& prims, const KdSahConfig& config, int depth_limit)
      : prims_(prims), config_(config), costs_(config.costs), depth_limit_(depth_limit) {}

  /// Builds the tree over the primitives `ids` (finite bounds) inside `box` into out.
  void build(const std::vector<uint32_t>& ids, const AABB& box, KdBuffer& out) const {
    auto attempt = [&](RefLedger* ledger, RefBudget budget) {
      ledger_ = ledger;
      out = KdBuffer{};
      build_node(make_root(ids, box), {0, budget}, out);
    };
    budget_exhausted_ = build_with_budget(ids.size(), config_.ref_budget, depth_limit_, attempt);
    ledger_ = nullptr;
  }
  /// True when the tree was built with the reference budget (build_with_budget).
  bool budget_exhausted() const { return budget_exhausted_; }

 private:
  KdEventNode make_root(const std::vector<uint32_t>& ids, const AABB& box) const {
    KdEventNode root;
    root.box = box;
    root.ids = ids;
    for (auto& ev : root.events) ev.resize(2 * ids.size());
    std::vector<uint8_t> used(ids.size() * 3);
    tbb::parallel_for(size_t(0), ids.size(), [&](size_t i) {
      const AABB cb = prims_.clipped_bounds(ids[i], box);
      for (int a = 0; a < 3; ++a) {
        const uint32_t key = uint32_t(i) << 2;
        KdEvent* slot = &root.events[a][2 * i];
        if (cb.lo[a] == cb.hi[a]) {
          slot[0] = {cb.lo[a], key | KdEvent::kPlanar};
          used[3 * i + a] = 1;
        } else {
          slot[0] = {cb.lo[a], key | KdEvent::kStart};
          slot[1] = {cb.hi[a], key | KdEvent::kEnd};
          used[3 * i + a] = 2;
        }
      }
    });
    for (int a = 0; a < 3; ++a) {
      std::vector<KdEvent>& ev = root.events[a];
      size_t k = 0;
      for (size_t i = 0; i < ids.size(); ++i)
        for (uint8_t j = 0; j < used[3 * i + a]; ++j) ev[k++] = ev[2 * i + j];
      ev.resize(k);
    }
    tbb::parallel_for(0, 3, [&](int a) { tbb::parallel_sort(root.events[a].begin(), root.events[a].end()); });
    return root;
  }

  /// Where a node sits: its depth and its reference budget.
  struct Path {
    int depth;
    RefBudget budget;
  };

  /// Appends a leaf of ids.
  void make_leaf(const std::vector<uint32_t>& ids, KdBuffer& out) const {
    if (ledger_) ledger_->add_leaf(ids.size());
    out.nodes.push_back(out.make_leaf(ids));
  }

  void build_node(KdEventNode&& node, Path path, KdBuffer& out) const {
    if (ledger_ && ledger_->over()) return;  // an abandoned attempt
    const size_t n = node.ids.size();
    KdSahChoice choice;
    if (n > 0 && path.depth < depth_limit_) choice = find_kd_sah_plane(costs_, node);
    const bool forced = choice.best.axis >= 0 && choice.best.cost >= costs_.leaf(n);  // max_leaf's split
    if (choice.best.axis < 0 || (forced && (config_.max_leaf == 0 || n <= config_.max_leaf)))
      return make_leaf(node.ids, out);
    const KdSahPlane& plane = forced ? choice.progress : choice.best;
    if (plane.axis < 0) return make_leaf(node.ids, out);
    const float split = plane.pos;
    KdEventNode left, right;
    partition(std::move(node), plane.axis, split, plane.planar_left, left, right);
    const size_t nl = left.ids.size(), nr = right.ids.size();
    if ((nl == n && nr == n) || (forced && std::max(nl, nr) == n) || !path.budget.allows(nl + nr)) {
      std::vector<uint32_t> ids = std::move(left.ids);  // all n when nl == n
      if (nl != n) ids = merged_ids(ids, right.ids);
      return make_leaf(ids, out);
    }
    if (ledger_) ledger_->add_children(nl + nr);
    const Path lp{path.depth + 1, path.budget.share(nl, nl + nr)};
    const Path rp{path.depth + 1, path.budget.share(nr, nl + nr)};
    const size_t self = out.nodes.size();
    out.nodes.push_back(KdNode::leaf(0, 0));
    if (n >= kParallelMin) {
      KdBuffer lb, rb;
      tbb::parallel_invoke([&] { build_node(std::move(left), lp, lb); },
                           [&] { build_node(std::move(right), rp, rb); });
      out.append(lb);
      out.nodes[self] = KdNode::interior(plane.axis, split, uint32_t(out.nodes.size()));
      out.append(rb);
    } else {
      build_node(std::move(left), lp, out);
      out.nodes[self] = KdNode::interior(plane.axis, split, uint32_t(out.nodes.size()));
      build_node(std::move(right), rp, out);
    }
  }

  /// The node's primitives from its two children's lists (each in the node's order): sorted, once each.
  static std::vector<uint32_t> merged_ids(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    std::vector<uint32_t> out(a.size() + b.size());
    std::merge(a.begin(), a.end(), b.begin(), b.end(), out.begin());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  /// Splits node's primitives and events at `split` on axis a into left and right (linear time).
  void partition(KdEventNode&& node, int a, float split, bool planar_left, KdEventNode& left,
                 KdEventNode& right) const {
    const size_t n = node.ids.size();
    const float margin = insertion_margin(node.box);
    left.box = node.box;
    right.box = node.box;
    left.box.hi[a] = split;
    right.box.lo[a] = split;
    // Side of each primitive (bit 0 left, bit 1 right), Wald and Havran's classification: ending at or
    // before the plane is left only, starting at or after it right only, planar in it on the chosen side.
    std::vector<uint8_t> side(n, 3);
    for (const KdEvent& e : node.events[a]) {
      const uint32_t t = e.local();
      if (e.type() == KdEvent::kEnd && e.pos <= split)
        side[t] = 1;
      else if (e.type() == KdEvent::kStart && e.pos >= split)
        side[t] = 2;
      else if (e.type() == KdEvent::kPlanar)
        side[t] = e.pos < split ? 1 : e.pos > split ? 2 : planar_left ? 1 : 2;
    }
    std::vector<uint32_t> to_left(n), to_right(n);
    for (size_t t = 0; t < n; ++t) {
      if (side[t] & 1) {
        to_left[t] = uint32_t(left.ids.size());
        left.ids.push_back(node.ids[t]);
      }
      if (side[t] & 2) {
        to_right[t] = uint32_t(right.ids.size());
        right.ids.push_back(node.ids[t]);
      }
    }
    for (int k = 0; k < 3; ++k) {
      const size_t m = node.events[k].size();
      left.events[k].reserve(m * left.ids.size() / n + 8);
      right.events[k].reserve(m * right.ids.size() / n + 8);
      split_events(node.events[k], side, to_left, to_right, left.events[k], right.events[k]);
      std::vector<KdEvent>().swap(node.events[k]);
    }
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

  /// Clips the primitives on both sides into child (perfect splits), sorts their events and merges them in.
  void add_straddlers(const std::vector<uint32_t>& ids, const std::vector<uint8_t>& side,
                      const std::vector<uint32_t>& to_child, float margin, KdEventNode& child) const {
    std::array<std::vector<KdEvent>, 3> extra;
    for (size_t t = 0; t < ids.size(); ++t) {
      if (side[t] != 3) continue;
      add_kd_events(clip_into_child(prims_, ids[t], child.box, margin), to_child[t], extra);
    }
    for (int k = 0; k < 3; ++k) {
      if (extra[k].empty()) continue;
      std::sort(extra[k].begin(), extra[k].end());
      std::vector<KdEvent> merged(child.events[k].size() + extra[k].size());
      std::merge(child.events[k].begin(), child.events[k].end(), extra[k].begin(), extra[k].end(),
                 merged.begin());
      child.events[k].swap(merged);
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
};

}  // namespace ab
