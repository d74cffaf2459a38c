// The BSP build with arbitrary split planes (Ize, Wald and Parker 2008, "Ray tracing with the BSP tree";
// Kammaje and Mora 2007): candidate planes (candidates.h) priced by the SAH over the node's convex cell
// (cell.h), and a conservative partition (a primitive within the insertion margin of the plane goes to both
// sides). Each triangle's part in the cell is kept from the parent and clipped by the one new plane per
// level. Termination on any input (issue 11): the SAH; shaves (one child keeps every primitive) as pbrt-v3's
// bad refines, limited per path; kdtree-sah's max_leaf split of a large node the SAH would keep; the
// reference budget (build_with_budget, refine_rules.h) as the safety net of the references, at most
// ref_budget per primitive, the tree unchanged on any input whose tree stays under it. Large nodes build
// their two subtrees in parallel, the below one into the parent's buffer and the above one into its own,
// appended after it (the same tree for any thread count); nodes of many primitives also clip them and
// measure their ranges in parallel.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <span>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "accel/bsp/candidates.h"
#include "accel/bsp/cell.h"
#include "accel/bsp/config.h"
#include "accel/bsp/node.h"
#include "accel/common/ref_frontier.h"
#include "accel/common/refine_rules.h"
#include "accel/core/clip.h"

namespace ab {

/// Builds BSP trees over a primitive set P.
template <class P>
class BspBuilder {
 public:
  /// Builder over prims with the tree's configuration, its resolved depth limit, its insertion margin and
  /// the origin of its frame (BspTree::frame_origin): planes, cells and parts are in that frame.
  BspBuilder(const P& prims, const BspConfig& config, int depth_limit, float margin, const vec3& origin)
      : prims_(prims), config_(config), depth_limit_(depth_limit), margin_(margin), origin_(origin) {}

  /// Builds over ids (finite bounds) inside box (in the builder's frame) into out.
  void build(std::vector<uint32_t> ids, const AABB& box, BspBuffer& out) const {
    BspBuffer first;  // the abandoned first attempt's nodes and planes: the second attempt's memo
    auto attempt = [&](RefLedger* ledger, RefBudget budget) {
      ledger_ = ledger;
      if (!ledger && config_.reuse_decisions) {
        first = std::move(out);
        first.refs = {};
        memo_ = &first;
      }
      out = BspBuffer{};
      NodePrims root = gather_root(ids, box);
      set_gain_floor(box, ids.size());
      count_frontier_root(ledger, root.size());
      const ConvexCell cell = ConvexCell::from_box(box, band_floor(box));
      if (ledger && config_.reuse_decisions)
        build_top(std::move(root), cell, Depth{0, 0, 0, budget}, out);
      else
        build_node(std::move(root), cell, Depth{0, 0, 0, budget}, 0, out);
    };
    budget_exhausted_ = build_with_budget(ids.size(), config_.ref_budget, depth_limit_, attempt);
    ledger_ = nullptr;
    memo_ = nullptr;
  }
  /// True when the tree was built with the reference budget (build_with_budget).
  bool budget_exhausted() const { return budget_exhausted_; }

 private:
  struct Choice {
    BspPlane plane;
    float cost = kInf;
  };
  /// The node's primitives that reach its cell, each with the support points of its part inside the cell's
  /// (grown) bounding box and half-spaces: classifying the clipped part, not the whole primitive, keeps long
  /// primitives from being duplicated into every cell their supporting line or plane crosses.
  struct NodePrims {
    std::vector<uint32_t> ids;
    /// Primitive k's points are pts[start[k], start[k + 1]); empty while no primitive is added, so an empty
    /// set (the children a split starts with, a node's set once it is split) allocates nothing.
    std::vector<uint32_t> start;
    std::vector<vec3> pts;
    size_t size() const { return ids.size(); }
    /// Appends primitive id with its k support points (one at a time: a range insert took the generic path).
    void add(uint32_t id, const vec3* p, int k) {
      if (start.empty()) start.push_back(0);
      ids.push_back(id);
      for (int j = 0; j < k; ++j) pts.push_back(p[j]);
      start.push_back(uint32_t(pts.size()));
    }
  };

  /// A half-space dot(n, x) <= offset bounding the cell (already grown by the margin).
  struct HalfSpace {
    vec3 n;
    float offset;
  };

  /// Box b grown by the insertion margin.
  AABB grown(const AABB& b) const { return {b.lo - vec3(margin_), b.hi + vec3(margin_)}; }

  /// The root's primitives, clipped to the root box.
  NodePrims gather_root(const std::vector<uint32_t>& ids, const AABB& box) const {
    const AABB g = grown(box);
    return collect(ids.size(), [&](size_t k, uint32_t& id, vec3* buf) {
      id = ids[k];
      return support_points(prims_, id, g, buf, origin_);
    });
  }

  /// The primitives k < count for which part(k, id, points) gives an id and points (their count; 0: the
  /// primitive is left out), in k's order. A large node's are made in chunks in parallel and joined (the
  /// same result: at 10M triangles the root's and the top levels' clipping ran on one core).
  template <class Part>
  NodePrims collect(size_t count, Part&& part) const {
    const size_t chunks = count >= kParallelPrims ? (count + kParallelGrain - 1) / kParallelGrain : 1;
    std::vector<NodePrims> pieces(chunks);
    auto fill = [&](size_t c) {
      vec3 buf[kMaxSupportPoints];
      uint32_t id = 0;
      for (size_t k = c * count / chunks, end = (c + 1) * count / chunks; k < end; ++k)
        if (const int m = part(k, id, buf); m > 0) pieces[c].add(id, buf, m);
    };
    if (chunks == 1) {
      fill(0);
      return std::move(pieces[0]);
    }
    isolated([&] { tbb::parallel_for(size_t(0), chunks, fill); });
    return join(pieces);
  }

  /// Runs f, whose parallel loop is one node's work, isolated (tbb::this_task_arena::isolate): a thread
  /// waiting for the loop's chunks runs none of another node's tasks, which would overwrite the kept
  /// (thread_local) buffers the caller is still using (classify's ranges, find_plane's surface).
  template <class F>
  static void isolated(F&& f) {
    tbb::this_task_arena::isolate(std::forward<F>(f));
  }

  /// The pieces' primitives one after another (collect), copied in parallel.
  static NodePrims join(const std::vector<NodePrims>& pieces) {
    std::vector<size_t> ids_at(pieces.size() + 1, 0), pts_at(pieces.size() + 1, 0);
    for (size_t c = 0; c < pieces.size(); ++c) {
      ids_at[c + 1] = ids_at[c] + pieces[c].size();
      pts_at[c + 1] = pts_at[c] + pieces[c].pts.size();
    }
    NodePrims out;
    out.ids.resize(ids_at.back());
    out.start.resize(ids_at.back() + 1);
    out.pts.resize(pts_at.back());
    isolated([&] {
      tbb::parallel_for(size_t(0), pieces.size(), [&](size_t c) {
        const NodePrims& p = pieces[c];
        std::copy(p.ids.begin(), p.ids.end(), out.ids.begin() + ptrdiff_t(ids_at[c]));
        std::copy(p.pts.begin(), p.pts.end(), out.pts.begin() + ptrdiff_t(pts_at[c]));
        for (size_t k = 0; k < p.size(); ++k)
          out.start[ids_at[c] + k + 1] = uint32_t(pts_at[c] + p.start[k + 1]);
      });
    });
    return out;
  }

  /// The primitives of the child on side `bit` (1 below, 2 above) of plane, whose cell is `cell`. A
  /// triangle's part is its part in the parent clipped by the one new half-space (grown by the margin) and
  /// the child's grown bounding box: one plane per level instead of the triangle clipped again by every
  /// plane on its path. Other primitive sets take their support points in the child's box again.
  NodePrims child_prims(const NodePrims& np, const std::vector<uint8_t>& sides, int bit,
                        const BspPlane& plane, const ConvexCell& cell) const {
    const AABB box = grown(cell.bounds());
    const HalfSpace cut =
        bit == 1 ? HalfSpace{plane.n, plane.d + margin_} : HalfSpace{-plane.n, margin_ - plane.d};
    const bool oblique = is_oblique(plane);
    if (np.size() >= kParallelPrims)
      return collect(np.size(), [&](size_t k, uint32_t& id, vec3* buf) {
        id = np.ids[k];
        return (sides[k] & bit) ? part_in_child(np, k, oblique ? &cut : nullptr, box, buf) : 0;
      });
    NodePrims out;
    size_t count = 0, points = 0;
    for (size_t k = 0; k < np.size(); ++k)
      if (sides[k] & bit) {
        ++count;
        points += np.start[k + 1] - np.start[k];
      }
    if (count == 0) return out;
    out.ids.reserve(count);  // one allocation each (a clip adds a point or two per cut part)
    out.start.reserve(count + 1);
    out.start.push_back(0);
    out.pts.reserve(points + 2 * count);
    vec3 buf[kMaxSupportPoints];
    for (size_t k = 0; k < np.size(); ++k) {
      if (!(sides[k] & bit)) continue;
      if (const int m = part_in_child(np, k, oblique ? &cut : nullptr, box, buf); m > 0)
        out.add(np.ids[k], buf, m);
    }
    return out;
  }

  /// Primitive k's part in a child cut by half-space cut (given for an oblique plane) of grown box box: a
  /// triangle's part clipped (clip_part), another primitive's support points in box.
  int part_in_child(const NodePrims& np, size_t k, const HalfSpace* cut, const AABB& box, vec3* out) const {
    if constexpr (std::is_same_v<P, TrianglePrims>) {
      return clip_part(np, k, cut, box, out);
    } else {
      return support_points(prims_, np.ids[k], box, out, origin_);
    }
  }

  /// Primitive k's part clipped by half-space cut (when given) and box, into out. Leaves a clip out (keeping
  /// a superset) when the polygon could outgrow its fixed capacity.
  static int clip_part(const NodePrims& np, size_t k, const HalfSpace* cut, const AABB& box, vec3* out) {
    ClipPolygon poly;
    const int capacity = int(poly.v.size());
    poly.n = std::min(int(np.start[k + 1] - np.start[k]), kMaxSupportPoints);
    for (int j = 0; j < poly.n; ++j) poly.v[size_t(j)] = np.pts[np.start[k] + size_t(j)];
    if (cut && poly.n + 2 < capacity) clip_polygon(poly, cut->n, cut->offset);
    AABB b;
    for (int j = 0; j < poly.n; ++j) b.extend(poly.v[j]);
    if (poly.n > 0 && !b.overlaps(box)) return 0;
    if (poly.n > 0 && !(box.contains(b.lo) && box.contains(b.hi)) && poly.n + 7 < capacity)
      clip_polygon_to_box(poly, box);
    for (int j = 0; j < poly.n; ++j) out[j] = poly.v[size_t(j)];
    return poly.n;
  }

  /// Depth of a node: all levels, and the splits with primitives on both sides. A split with an empty side
  /// (cutting off empty space, often a corner of the cell by an oblique plane) never puts an entry on the
  /// traversal stack, so only the other splits count against max_depth; the levels have their own bound.
  /// With the shaves on the path (bad refines) and the node's reference budget.
  struct Depth {
    int levels = 0, splits = 0, shaves = 0;
    RefBudget budget;
    /// The nearest ancestor of more than kGainAnchorMin primitives (none: area 0): its cell's area and
    /// min_gain over its primitives, the minimum-gain rule's local reference (kGainAnchorMin).
    float anchor_area = 0.0f, anchor_floor = 0.0f;
  };
  static constexpr int kEmptyCutLevels = 32;

  /// The node's plane, or a leaf: the SAH's cheapest plane when it beats the leaf; else, for a node of more
  /// than max_leaf primitives, the cheapest plane that leaves fewer on each side (kdtree-sah's rule).
  struct Decision {
    BspPlane plane;
    bool split = false, forced = false;
  };
  Decision decide(const NodePrims& np, const ConvexCell& cell, const Depth& depth) const {
    const size_t n = np.size();
    if (n <= 1 || depth.splits >= depth_limit_ || depth.levels >= depth_limit_ + kEmptyCutLevels) return {};
    const RayShares share = ray_shares(n, cell, depth);
    auto ok = [&](float split) {
      return pays(n, share.root, split, gain_floor_) ||
             (share.local >= 0.0f && pays(n, share.local, split, depth.anchor_floor));
    };
    if (!ok((1.0f - config_.costs.empty_bonus) * config_.costs.traversal)) return {};
    const bool shave_ok =
        config_.bad_refines == 0 || n <= kFreeShaveSize || depth.shaves + 1 < config_.bad_refines;
    Choices c = find_plane(np, cell, shave_ok, large_node(n));
    // A large node whose axis planes neither beat the leaf nor make progress tries the `directions` and
    // the autopartition after all: at a fan's centre (every triangle shares a vertex at the cell's
    // corner) only a plane through that vertex at another angle separates them.
    if (large_node(n) && !(c.best.cost < config_.costs.leaf(n)) && !(c.progress.cost < kInf))
      c = find_plane(np, cell, shave_ok, false);
    if (c.best.cost < config_.costs.leaf(n) && ok(c.best.cost)) return {c.best.plane, true, false};
    if (config_.max_leaf > 0 && n > config_.max_leaf && c.progress.cost < kInf)
      return {c.progress.plane, true, true};
    return {};
  }

  /// The minimum-gain rule (min_gain). The SAH's expected cost of a tree is the sum over its nodes of the
  /// chance that a ray through the root's cell reaches the node's, area(cell) / area(root), times the node's
  /// own cost (MacDonald and Booth 1990, the expected-cost model; Goldsmith and Salmon 1987), and the greedy
  /// SAH build splits a node whenever the split is cheaper than the leaf (Wald and Havran 2006's termination
  /// criterion), however little that saves the tree. On thin geometry and fine tessellations most nodes hold
  /// 2-15 pieces in cells so small that their splits save the tree less than a millionth of a test per ray,
  /// and each costs microseconds to price (20k `needles`: 66 nodes per triangle). So a node of at most
  /// max_leaf primitives splits only when share x (leaf - split) >= min_gain / N: a floor on the split's own
  /// saving in the tree's expected cost per ray, scaled by 1 / N as the nodes' shares are. Each node it keeps
  /// a leaf gives up less than min_gain / N of its best split's saving (its subtree's further splits are not
  /// priced), and those nodes are leaves of the tree, so the tree's cost grows by less than min_gain x
  /// leaves / N. A node whose share bounds every split's saving below the floor (no split costs less than
  /// (1 - empty_bonus) x traversal) is a leaf without pricing its planes. The floor is ours (measured in
  /// docs/structures.md), on the expected-cost model of the papers above. A split that misses it against
  /// the root may still pass it against a large ancestor (kGainAnchorMin).
  void set_gain_floor(const AABB& box, size_t n) const {
    root_area_ = ConvexCell::from_box(box, band_floor(box)).area();
    gain_floor_ = config_.min_gain / float(std::max<size_t>(n, 1));
  }
  /// A node's shares of the rays: area(cell) / area(root), and area(cell) / area(anchor) against its
  /// local anchor (kGainAnchorMin); -1 where the rule does not apply.
  struct RayShares {
    float root = -1.0f, local = -1.0f;
  };
  /// The node's shares when the minimum-gain rule applies to it (at most max_leaf primitives, min_gain > 0,
  /// a root of some area; the local one with an anchor), from one computation of the cell's area.
  RayShares ray_shares(size_t n, const ConvexCell& cell, const Depth& depth) const {
    if (!(gain_floor_ > 0.0f && root_area_ > 0.0f) || (config_.max_leaf > 0 && n > config_.max_leaf))
      return {};
    const float area = cell.area();
    return {area / root_area_, depth.anchor_area > 0.0f ? area / depth.anchor_area : -1.0f};
  }
  /// True when a split of a node of n primitives whose ray share is `share` at cost `split` (per unit of the
  /// node's area) saves the tree at least `floor` (always, when the rule does not apply: share < 0).
  bool pays(size_t n, float share, float split, float floor) const {
    return share < 0.0f || share * (config_.costs.leaf(n) - split) >= floor;
  }
  /// The local reference of the minimum-gain rule. The shares above are those of rays uniform over the
  /// root's cell, so a small object in a large scene (the bunny on a ground square 100 times its size, the
  /// camera on the bunny) has every node's share small, and the floor made them leaves: 5,195 nodes and
  /// 33.5 triangle tests per ray, against 3.2 with min_gain=0. A split also pays when it passes the same
  /// floor against its nearest ancestor of more than kGainAnchorMin primitives, as if the rays were uniform
  /// over that ancestor's cell (share area(cell) / area(ancestor), floor min_gain / its primitives): 3.4
  /// tests per ray there. Either rule suffices, so no split the root's rule takes is lost. 4096: the
  /// ordinary inputs measured (the bunny, the 100k sphereflake and soup, 20k and 200k `needles`, `far`)
  /// keep their trees node for node; with 1024 20k `needles` grew from 0.78M to 0.88M nodes.
  static constexpr size_t kGainAnchorMin = 4096;

  /// The first attempt's tree as the memo of the budgeted second attempt (build_with_budget): a node's
  /// decision depends only on its primitives, cell and depth, never on its budget, which only turns a split
  /// into a leaf, so both attempts take the same paths down to the first node the budget stops, and the
  /// second takes each decision the first one made (an interior node: its plane; a leaf: a leaf) instead of
  /// evaluating the candidates again, which is most of a node's cost. Nodes the first attempt abandoned
  /// (kAbandoned) and those below it are decided again. The same tree as without the memo, for any thread
  /// count (a remembered decision is the one decide gives, whichever nodes the first attempt reached).
  Decision memoized_decision(const NodePrims& np, const ConvexCell& cell, const Depth& depth,
                             uint32_t at) const {
    if (memo_ && at != kNoMemo) {
      const BspNode& m = memo_->nodes[at];
      if (!m.is_leaf()) return {memo_->payload[m.plane()], true, false};
      if (m.count() != kAbandoned.count()) return {};
    }
    return decide(np, cell, depth);
  }
  /// The memo node of child `above` (0 below, 1 above) of memo node at (kNoMemo: none).
  uint32_t memo_child(uint32_t at, int above) const {
    if (!memo_ || at == kNoMemo || memo_->nodes[at].is_leaf()) return kNoMemo;
    return above ? memo_->nodes[at].above() : at + 1;
  }
  static constexpr uint32_t kNoMemo = ~0u;
  /// The node an abandoned first attempt writes where it stopped (no real leaf holds 2^31 - 1 references).
  static inline const BspNode kAbandoned = BspNode::leaf(0, (1u << 31) - 1);

  /// Appends a leaf of the node's primitives.
  void make_leaf(const NodePrims& np, BspBuffer& out) const { out.nodes.push_back(out.make_leaf(np.ids)); }

  /// A node's decision carried out on its primitives: the plane's sides of each primitive and the counts,
  /// or a leaf (no plane, an empty or undivided split, or one the budget does not allow).
  struct Step {
    Decision d;
    std::vector<uint8_t> sides;
    size_t nl = 0, nr = 0;
    bool leaf = true;
  };
  /// The node's step; a split is counted in the first attempt's ledger.
  Step step(const NodePrims& np, const ConvexCell& cell, const Depth& depth, uint32_t at) const {
    const size_t n = np.size();
    Step s;
    s.d = memoized_decision(np, cell, depth, at);
    if (s.d.split) classify(np, s.d.plane, s.sides, s.nl, s.nr);
    const size_t nl = s.nl, nr = s.nr;
    s.leaf = (nl == 0 && nr == 0) || (nl == n && nr == n) || (s.d.forced && std::max(nl, nr) == n) ||
             !depth.budget.allows(nl + nr);
    if (!s.leaf) count_frontier_split(ledger_, n, nl, nr);
    return s;
  }

  /// The two children of a node that splits (step): their primitives, cells and depths.
  struct Children {
    NodePrims prims[2];
    ConvexCell cells[2];
    Depth depths[2];
  };
  Children children(const NodePrims& np, const ConvexCell& cell, const Depth& depth, const Step& s) const {
    const size_t n = np.size(), nl = s.nl, nr = s.nr;
    Children c;
    // An empty child is a leaf whose cell is never read: only the others' cells are made (at 1M
    // triangles a fifth of the parts).
    std::tie(c.cells[0], c.cells[1]) = cell.parts(s.d.plane, nl > 0, nr > 0);
    c.prims[0] = child_prims(np, s.sides, 1, s.d.plane, c.cells[0]);
    c.prims[1] = child_prims(np, s.sides, 2, s.d.plane, c.cells[1]);
    const bool shave = is_shave(nl, nr, n, !s.d.forced,
                                [&] { return (nl >= nr ? c.cells[0] : c.cells[1]).area() / cell.area(); });
    const int levels = depth.levels + 1, splits = depth.splits + int(nl > 0 && nr > 0);
    const int shaves = depth.shaves + int(shave);
    float aa = depth.anchor_area, af = depth.anchor_floor;  // the children's anchor (kGainAnchorMin)
    if (n > kGainAnchorMin) aa = cell.area(), af = config_.min_gain / float(n);
    c.depths[0] = Depth{levels, splits, shaves, depth.budget.share(nl, nl + nr), aa, af};
    c.depths[1] = Depth{levels, splits, shaves, depth.budget.share(nr, nl + nr), aa, af};
    return c;
  }

  /// Builds the node of primitives np in cell into out; `at`: its node in the memo (memoized_decision).
  void build_node(NodePrims&& np, const ConvexCell& cell, Depth depth, uint32_t at, BspBuffer& out) const {
    if (ledger_ && ledger_->over()) return out.nodes.push_back(kAbandoned);
    const Step s = step(np, cell, depth, at);
    if (s.leaf) return make_leaf(np, out);
    grow(std::move(np), cell, depth, at, s, out);
  }

  /// Builds the subtrees of a node that splits (step s) into out, after the node itself.
  void grow(NodePrims&& np, const ConvexCell& cell, const Depth& depth, uint32_t at, const Step& s,
            BspBuffer& out) const {
    const size_t n = np.size();
    Children c = children(np, cell, depth, s);
    np = NodePrims{};
    const uint32_t lat = memo_child(at, 0), rat = memo_child(at, 1);
    if (n >= kParallelMin) {
      // The below subtree goes straight into out, after this node, as the serial build writes it; only
      // the above one is built into a buffer of its own and appended (each subtree was copied at every
      // parallel level above it: at 10M triangles 15 levels of the whole tree's nodes).
      BspBuffer rb;
      write_interior(
          out, s.d.plane,
          [&](BspBuffer& o) {
            tbb::parallel_invoke(
                [&] { build_node(std::move(c.prims[0]), c.cells[0], c.depths[0], lat, o); },
                [&] { build_node(std::move(c.prims[1]), c.cells[1], c.depths[1], rat, rb); });
          },
          [&](BspBuffer& o) { o.append(rb); });
    } else {
      write_interior(
          out, s.d.plane,
          [&](BspBuffer& o) { build_node(std::move(c.prims[0]), c.cells[0], c.depths[0], lat, o); },
          [&](BspBuffer& o) { build_node(std::move(c.prims[1]), c.cells[1], c.depths[1], rat, o); });
    }
  }

  /// Writes an interior node of plane into out, then its below subtree (below(out)) and its above one
  /// (above(out)): the depth-first layout, the below child next to its parent.
  template <class Below, class Above>
  static void write_interior(BspBuffer& out, const BspPlane& plane, Below&& below, Above&& above) {
    const size_t self = out.nodes.size();
    const uint32_t index = uint32_t(out.payload.size());
    out.payload.push_back(plane);
    out.nodes.push_back(BspNode::leaf(0, 0));
    below(out);
    out.nodes[self] = BspNode::interior(index, uint32_t(out.nodes.size()));
    above(out);
  }

  /// A node of the first attempt's breadth-first top (build_top).
  struct TopNode {
    NodePrims np;
    ConvexCell cell;
    Depth depth;
    BspPlane plane;
    uint32_t below = 0, above = 0;  ///< the children, when split
    bool split = false;
    BspBuffer sub;  ///< a leaf's node, or the subtree of a node the top left to the depth-first build
  };

  /// The first attempt's top levels built breadth first, each level's nodes in parallel, until a level
  /// holds more than min(ref_budget x N, kTopRefs) references or too many nodes (kTopNodes); then the nodes
  /// left are built depth first (build_node), each into its own buffer, in parallel, and everything is laid
  /// out as build_node would have written it (the same decisions, so the same tree). A tree over the budget
  /// passes it as its frontier (ref_frontier.h) does, and breadth first that is after its first few
  /// duplicating levels (large overlapping triangles: every split copies most of them): depth first, the
  /// first subtree alone was built to its leaves before the others' copies were counted (20k `large`: 362,805
  /// nodes made before the abandon, against 40,481 in the budgeted tree).
  void build_top(NodePrims&& root, const ConvexCell& cell, const Depth& depth, BspBuffer& out) const {
    std::vector<TopNode> t(1);
    t[0].np = std::move(root);
    t[0].cell = cell;
    t[0].depth = depth;
    const double limit = std::min(config_.ref_budget * double(t[0].np.size()), double(kTopRefs));
    const size_t max_nodes = std::min(kTopNodesMax, t[0].np.size());
    std::vector<uint32_t> level{0};
    size_t previous = 0;  // the references of the level before
    while (!level.empty() && !ledger_->over()) {
      size_t refs = 0;
      for (uint32_t i : level) refs += t[i].np.size();
      const bool duplicating = double(refs) > kTopGrowth * double(previous);
      if (double(refs) > limit || level.size() > max_nodes || (level.size() > kTopNodes && !duplicating))
        break;
      previous = refs;
      std::vector<Step> steps(level.size());
      tbb::parallel_for(size_t(0), level.size(), [&](size_t k) {
        const TopNode& x = t[level[k]];
        steps[k] = step(x.np, x.cell, x.depth, kNoMemo);
      });
      if (ledger_->over()) break;
      level = top_children(t, level, steps);
    }
    tbb::parallel_for(size_t(0), level.size(), [&](size_t k) {
      TopNode& x = t[level[k]];
      build_node(std::move(x.np), x.cell, x.depth, kNoMemo, x.sub);
    });
    lay_out(t, out);
  }

  /// The next level of build_top: the children of the level's nodes that split (in parallel, appended in
  /// the level's order); the leaves made.
  std::vector<uint32_t> top_children(std::vector<TopNode>& t, const std::vector<uint32_t>& level,
                                     const std::vector<Step>& steps) const {
    std::vector<Children> kids(level.size());
    tbb::parallel_for(size_t(0), level.size(), [&](size_t k) {
      TopNode& x = t[level[k]];
      if (steps[k].leaf)
        make_leaf(x.np, x.sub);
      else
        kids[k] = children(x.np, x.cell, x.depth, steps[k]);
    });
    std::vector<uint32_t> next;
    for (size_t k = 0; k < level.size(); ++k) {
      const uint32_t i = level[k];
      t[i].np = NodePrims{};
      t[i].cell = ConvexCell{};
      if (steps[k].leaf) continue;
      t[i].split = true;
      t[i].plane = steps[k].d.plane;
      for (int side = 0; side < 2; ++side) {
        (side ? t[i].above : t[i].below) = uint32_t(t.size());
        next.push_back(uint32_t(t.size()));
        TopNode child;
        child.np = std::move(kids[k].prims[side]);
        child.cell = std::move(kids[k].cells[side]);
        child.depth = kids[k].depths[side];
        t.push_back(std::move(child));
      }
    }
    return next;
  }

  /// Where a node of build_top's tree and its subtree go in the output: its first node, reference and plane.
  struct TopPlace {
    size_t node = 0, ref = 0, payload = 0;
  };

  /// Places node i's subtree from `at` on in build_node's order (a split node: itself and its plane, its
  /// below subtree, its above one) into places; returns the place after it.
  static TopPlace place(const std::vector<TopNode>& t, uint32_t i, TopPlace at,
                        std::vector<TopPlace>& places) {
    places[i] = at;
    const BspBuffer& s = t[i].sub;
    if (!t[i].split) return {at.node + s.nodes.size(), at.ref + s.refs.size(), at.payload + s.payload.size()};
    at = place(t, t[i].below, {at.node + 1, at.ref, at.payload + 1}, places);
    return place(t, t[i].above, at, places);
  }

  /// Writes build_top's tree into the empty out in build_node's order: every node's place first (serial,
  /// over the top's nodes only), then each node's part in parallel, a subtree rebased into its place as
  /// TreeBuffer::append would (appended one after another, the whole tree was copied on one core). A root
  /// the top left to the depth-first build (a 10M input's, when the top stops at once) is moved.
  static void lay_out(std::vector<TopNode>& t, BspBuffer& out) {
    if (!t[0].split) {
      out = std::move(t[0].sub);
      return;
    }
    std::vector<TopPlace> places(t.size());
    const TopPlace end = place(t, 0, TopPlace{}, places);
    out.nodes.assign(end.node, BspNode::leaf(0, 0));
    out.refs.resize(end.ref);
    out.payload.resize(end.payload);
    tbb::parallel_for(size_t(0), t.size(), [&](size_t i) {
      const TopPlace& at = places[i];
      if (t[i].split) {
        out.payload[at.payload] = t[i].plane;
        out.nodes[at.node] = BspNode::interior(uint32_t(at.payload), uint32_t(places[t[i].above].node));
        return;
      }
      const BspBuffer& s = t[i].sub;
      const TreeOffsets offsets{uint32_t(at.node), uint32_t(at.ref), uint32_t(at.payload)};
      for (size_t j = 0; j < s.nodes.size(); ++j) {
        BspNode n = s.nodes[j];
        n.rebase(offsets);
        out.nodes[at.node + j] = n;
      }
      std::copy(s.refs.begin(), s.refs.end(), out.refs.begin() + ptrdiff_t(at.ref));
      std::copy(s.payload.begin(), s.payload.end(), out.payload.begin() + ptrdiff_t(at.payload));
    });
  }

  /// The signed-distance ranges [lo[k], hi[k]] of every primitive's support points from the plane through
  /// the origin with normal n: every point's distance in one loop (vectorized), then each primitive's
  /// extremes (from a plane at offset d the ranges are these less d: subtracting d keeps the order).
  static void ranges(const NodePrims& np, const vec3& n, std::vector<float>& dots, float* lo, float* hi) {
    if (np.size() >= kParallelPrims) {  // a large node's in parallel, each point's distance as below
      isolated([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, np.size(), kParallelGrain), [&](const auto& r) {
          for (size_t k = r.begin(); k < r.end(); ++k) {
            float a = kInf, b = -kInf;
            for (uint32_t j = np.start[k]; j < np.start[k + 1]; ++j) {
              const vec3& p = np.pts[j];
              const float t = n.x * p.x + n.y * p.y + n.z * p.z;
              a = std::min(a, t);
              b = std::max(b, t);
            }
            lo[k] = a;
            hi[k] = b;
          }
        });
      });
      return;
    }
    const size_t m = np.pts.size();
    grow_buffer(dots, m);
    const vec3* __restrict p = np.pts.data();
    float* __restrict out = dots.data();
    const float x = n.x, y = n.y, z = n.z;
    for (size_t j = 0; j < m; ++j) out[j] = x * p[j].x + y * p[j].y + z * p[j].z;
    for (size_t k = 0; k < np.size(); ++k) {
      float a = kInf, b = -kInf;
      for (uint32_t j = np.start[k]; j < np.start[k + 1]; ++j) {
        a = std::min(a, out[j]);
        b = std::max(b, out[j]);
      }
      lo[k] = a;
      hi[k] = b;
    }
  }

  /// The cell's surface area and its reciprocal.
  struct CellArea {
    float area, inv;
  };

  /// SAH cost of a plane (the one cost model, SahCosts::split) from the areas of the two parts and the
  /// counts on each side. A plane that does not cut the cell (a part of (almost) no area) is no candidate:
  /// it would only earn the empty bonus and repeat itself down to the depth limit, so it costs infinity.
  float cost(const CellArea& cell, float al, float ar, size_t nl, size_t nr) const {
    if (!(std::min(al, ar) * cell.inv > 1e-5f)) return kInf;
    return config_.costs.split(cell.area, al, nl, ar, nr);
  }

  /// The cheapest plane, and the cheapest one that leaves fewer than the node's n primitives on each side.
  struct Choices {
    Choice best, progress;
  };

  /// A shave: a plane whose larger side keeps more than kShaveShare of the node's primitives while most of
  /// the smaller side's are copies (on both sides), so the larger child does nearly all the node's work and
  /// the smaller one mostly copies. On large overlapping triangles the SAH prices such corner cuts of the
  /// cell just below the leaf again and again (2000, 1999, 1998, ... triangles), which grows the nodes and
  /// references without bound; they are pbrt-v3's bad refines here (Pharr, Jakob and Humphreys 2016, 4.4.2:
  /// a refinement that does not reduce the work), and a node of more than kFreeShaveSize primitives whose
  /// path already holds bad_refines - 1 of them considers none. Splits that peel off a cluster of the
  /// node's own (the 100k stadium's) are not shaves.
  ///
  /// Except (shave_area) a split the SAH prices below the leaf whose larger child keeps at most shave_area
  /// of the cell's surface area: it shrinks the cell of nearly all the primitives instead of cutting a
  /// corner off it, so the larger child is hit by fewer rays. At a fan's centre, where every triangle meets
  /// the shared vertex, every plane keeps nearly all on the vertex's side, and only such splits shrink the
  /// cell around it (200k `fan`: leaves of 25-30k triangles at the vertex, 5,224 tests per ray). `share`
  /// gives the larger child's area share (evaluated only for such a split).
  template <class Share>
  bool is_shave(size_t nl, size_t nr, size_t n, bool below_leaf, Share&& share) const {
    const size_t small = std::min(nl, nr), both = nl + nr > n ? nl + nr - n : 0;
    if (!(small > 0 && double(std::max(nl, nr)) > kShaveShare * double(n) && 2 * both > small)) return false;
    return !(below_leaf && config_.shave_area > 0.0f && share() <= config_.shave_area);
  }
  /// A split whose larger child keeps more than this share of the node's primitives is a shave.
  static constexpr double kShaveShare = 0.9;
  /// Nodes of at most this many primitives shave freely: their shaves are cheap (the limit there cost the
  /// 10k sphereflake 9% more triangle tests per ray).
  static constexpr size_t kFreeShaveSize = 64;

  /// Keeps plane at cost c in the choices (nl and nr primitives below and above, of n; al and ar the areas
  /// of its parts).
  void keep(Choices& ch, const BspPlane& plane, const CellArea& cell, float al, float ar, size_t nl,
            size_t nr, size_t n, bool shave_ok) const {
    const float c = cost(cell, al, ar, nl, nr);
    if (!shave_ok &&
        is_shave(nl, nr, n, c < config_.costs.leaf(n), [&] { return (nl >= nr ? al : ar) * cell.inv; }))
      return;
    if (c < ch.best.cost) ch.best = {plane, c};
    if (nl < n && nr < n && c < ch.progress.cost) ch.progress = {plane, c};
  }

  /// The buffers of binned_planes, kept over the directions of a node.
  struct PlaneScratch {
    std::vector<float> lo, hi, d, al, ar;
    std::vector<uint32_t> nl, nr, starts, ends;
    std::vector<float> dots;  ///< every support point's distance (ranges)
    /// ranges_along's per-primitive rows (kBatchDirs lows, then as many highs) and its per-direction
    /// ranges, direction i's from i n.
    std::vector<float> rows, dir_lo, dir_hi;
  };

  /// The node's best planes over its candidates (binned_planes per direction, autopartition_planes);
  /// `large`: the three axes only.
  Choices find_plane(const NodePrims& np, const ConvexCell& cell, bool shave_ok, bool large) const {
    Choices ch;
    // Buffers kept from node to node on each thread (no call below builds another node); a large node's
    // are its own, so no thread keeps a large buffer after the build.
    thread_local CellSurface surface;
    thread_local PlaneScratch kept;
    PlaneScratch own;
    PlaneScratch& scratch = np.size() <= kKeptScratchMax ? kept : own;
    if (large && cell.is_box()) {  // a box cell cut by axis planes: the k-d tree's closed-form areas
      const BoxSurface box(cell);
      const float area = box.area();
      if (!(area > 0.0f)) return ch;
      for (size_t i = 0; i < 3; ++i)
        measured_planes(np, box, CellArea{area, 1.0f / area}, bsp_directions()[i], shave_ok, scratch, ch);
      return ch;
    }
    surface.assign(cell);
    const float area = surface.area();
    if (!(area > 0.0f)) return ch;
    const CellArea cell_area{area, 1.0f / area};
    // Large nodes: the three axes only (binned), no diagonals and no autopartition, so such a node costs
    // O(N) with the k-d tree's constant and, as every ancestor of a large node is larger, the cells above
    // oblique_max stay boxes (unless the axes fail: decide). The size switch is the binned-above /
    // exact-below switch of the SAH k-d tree builds (Hunt, Mark and Stoll 2006; Popov, Guenther, Seidel and
    // Slusallek 2006; discussed by Wald and Havran 2006) applied to the set of directions: a restricted BSP
    // (Kammaje and Mora 2007; Budge et al. 2008) whose restriction is the three axes above the size and the
    // `directions` fixed directions (of Kammaje and Mora's 13) and the triangles' own planes (Ize, Wald and
    // Parker 2008) below it.
    const auto& dirs = bsp_directions();
    const std::span<const size_t> set = bsp_direction_set(large ? 3 : config_.directions);
    // A large node's axes, and a huge node's directions (ranges in parallel), one direction at a time.
    if (large || np.size() >= kParallelPrims) {
      for (size_t i : set) measured_planes(np, surface, cell_area, dirs[i], shave_ok, scratch, ch);
      if (!large) autopartition_planes(np, surface, cell_area, shave_ok, scratch, ch);
      return ch;
    }
    vec3 along[kBatchDirs];
    for (size_t k = 0; k < set.size(); ++k) along[k] = dirs[set[k]];
    ranges_along(np, std::span<const vec3>(along, set.size()), scratch);
    for (size_t k = 0; k < set.size(); ++k) {
      const float *lo = scratch.dir_lo.data() + k * np.size(), *hi = scratch.dir_hi.data() + k * np.size();
      binned_planes(np, surface, cell_area, dirs[set[k]], lo, hi, shave_ok, scratch, ch);
    }
    autopartition_planes(np, surface, cell_area, shave_ok, scratch, ch);
    return ch;
  }

  /// binned_planes along dir with the primitives' ranges measured here (ranges).
  template <class Surface>
  void measured_planes(const NodePrims& np, const Surface& surface, const CellArea& cell_area,
                       const vec3& dir, bool shave_ok, PlaneScratch& s, Choices& ch) const {
    grow_buffer(s.lo, np.size());
    grow_buffer(s.hi, np.size());
    ranges(np, dir, s.dots, s.lo.data(), s.hi.data());
    binned_planes(np, surface, cell_area, dir, s.lo.data(), s.hi.data(), shave_ok, s, ch);
  }

  /// The ranges (ranges) of every primitive of a node of fewer than kParallelPrims along each direction of
  /// set (at most kBatchDirs), into s.dir_lo and s.dir_hi, in one pass over the support points: every
  /// point's distances from all the directions' planes in vectors of 8 directions (GCC's vector extension),
  /// each lane with ranges' operations in its order (the same bits), instead of one pass per direction (9
  /// fixed ones and about 4 of the autopartition's a node: ranges was a tenth of 5k `needles`'
  /// instructions).
  static void ranges_along(const NodePrims& np, std::span<const vec3> set, PlaneScratch& s) {
    using F = float __attribute__((vector_size(8 * sizeof(float))));
    constexpr size_t kV = kBatchDirs / 8;
    F x[kV] = {}, y[kV] = {}, z[kV] = {};
    for (size_t i = 0; i < set.size() && i < kBatchDirs; ++i) {
      const vec3& d = set[i];
      x[i / 8][i % 8] = d.x;
      y[i / 8][i % 8] = d.y;
      z[i / 8][i % 8] = d.z;
    }
    const size_t n = np.size();
    grow_buffer(s.rows, 2 * kBatchDirs * n);
    for (size_t k = 0; k < n; ++k) {
      F lo[kV], hi[kV];
      for (size_t v = 0; v < kV; ++v) {
        lo[v] = kInf - F{};
        hi[v] = -kInf - F{};
      }
      for (uint32_t j = np.start[k]; j < np.start[k + 1]; ++j) {
        const vec3& p = np.pts[j];
        const F px = p.x - F{}, py = p.y - F{}, pz = p.z - F{};  // broadcasts (x - 0 is x)
        for (size_t v = 0; v < kV; ++v) {
          const F t = x[v] * px + y[v] * py + z[v] * pz;
          lo[v] = t < lo[v] ? t : lo[v];  // std::min(lo, t)
          hi[v] = hi[v] < t ? t : hi[v];  // std::max(hi, t)
        }
      }
      std::memcpy(&s.rows[2 * kBatchDirs * k], lo, sizeof(lo));
      std::memcpy(&s.rows[2 * kBatchDirs * k + kBatchDirs], hi, sizeof(hi));
    }
    grow_buffer(s.dir_lo, set.size() * n);
    grow_buffer(s.dir_hi, set.size() * n);
    for (size_t i = 0; i < set.size(); ++i)
      for (size_t k = 0; k < n; ++k) {
        s.dir_lo[i * n + k] = s.rows[2 * kBatchDirs * k + i];
        s.dir_hi[i * n + k] = s.rows[2 * kBatchDirs * k + kBatchDirs + i];
      }
  }
  /// Directions ranges_along measures at once (two vectors of 8: the 13 of bsp_directions, or the
  /// autopartition's planes, at most).
  static constexpr size_t kBatchDirs = 16;

  /// True for a node of more than oblique_max primitives: the three axes only (find_plane).
  bool large_node(size_t n) const { return config_.oblique_max > 0 && n > config_.oblique_max; }

  /// The supporting planes of up to `autopartition` of the node's triangles (Ize, Wald and Parker 2008).
  void autopartition_planes(const NodePrims& np, const CellSurface& surface, const CellArea& cell_area,
                            bool shave_ok, PlaneScratch& scratch, Choices& ch) const {
    const size_t k = std::min<size_t>(np.size(), size_t(config_.autopartition));
    grow_buffer(scratch.lo, np.size());
    grow_buffer(scratch.hi, np.size());
    // Every sampled triangle's plane first: the triangles are read from the whole mesh, mostly cache
    // misses (a third of this function's time at 1M triangles), and independent reads overlap.
    thread_local std::vector<BspPlane> planes;  // used only here: no call below builds a node
    thread_local std::vector<uint8_t> valid;
    grow_buffer(planes, k);
    grow_buffer(valid, k);
    for (size_t j = 0; j < k; ++j)
      valid[j] = supporting_plane(prims_, np.ids[j * np.size() / k], planes[j], origin_);
    // The valid planes' ranges at once (ranges_along) for a node below kParallelPrims; the b-th valid
    // plane's at b n.
    const bool batch = np.size() < kParallelPrims && k <= kBatchDirs;
    if (batch) {
      vec3 along[kBatchDirs];
      size_t count = 0;
      for (size_t j = 0; j < k; ++j)
        if (valid[j]) along[count++] = planes[j].n;
      ranges_along(np, std::span<const vec3>(along, count), scratch);
    }
    for (size_t j = 0, b = 0; j < k; ++j) {
      if (!valid[j]) continue;
      const BspPlane& own = planes[j];
      // The plane itself and the plane moved two margins to either side, which puts the primitives
      // lying in it on one side only (like the planar events of Wald and Havran 2006).
      const float d[3] = {own.d, own.d - 2.0f * margin_, own.d + 2.0f * margin_};
      float al[3], ar[3];
      surface.areas(own.n, d, al, ar);
      size_t nl[3] = {0, 0, 0}, nr[3] = {0, 0, 0};
      const float *plo = scratch.lo.data(), *phi = scratch.hi.data();
      if (batch) {
        plo = scratch.dir_lo.data() + b * np.size();
        phi = scratch.dir_hi.data() + b * np.size();
        ++b;
      } else {
        ranges(np, own.n, scratch.dots, scratch.lo.data(), scratch.hi.data());
      }
      const float half = 0.5f * margin_;
      for (size_t i = 0; i < np.size(); ++i) {
        const float lo = plo[i] - own.d, hi = phi[i] - own.d;  // for the three planes, shifted
        for (int m = 0; m < 3; ++m) {                          // side_bits without branches
          uint32_t below, above;
          sides_of(lo - (d[m] - own.d), hi - (d[m] - own.d), half, below, above);
          nl[m] += size_t(below);
          nr[m] += size_t(above);
        }
      }
      for (int m = 0; m < 3; ++m)
        keep(ch, BspPlane{own.n, d[m]}, cell_area, al[m], ar[m], nl[m], nr[m], np.size(), shave_ok);
    }
  }

  /// Candidate planes of direction dir. A node of at most `bins` primitives tries the planes at the ends of
  /// each primitive's extent (the primitive is classified on one side only), like the events of a k-d sweep;
  /// a larger node the bin boundaries of the extents (Wald 2007's binning, a primitive counted on every side
  /// its extent reaches) and two planes just outside all extents. A plane with an empty side must cut off at
  /// least 1/bins of the cell's extent, or each node would shave off another sliver (its primitives clipped a
  /// little tighter) down to the depth limit. Surface: the cell's (CellSurface) or a box cell's (BoxSurface).
  template <class Surface>
  void binned_planes(const NodePrims& np, const Surface& surface, const CellArea& cell_area, const vec3& dir,
                     const float* lo, const float* hi, bool shave_ok, PlaneScratch& s, Choices& ch) const {
    const size_t n = np.size();
    std::vector<float>&d = s.d, &al = s.al, &ar = s.ar;
    std::vector<uint32_t>&nl = s.nl, &nr = s.nr;
    d.clear();
    nl.clear();
    nr.clear();
    float range_lo = kInf, range_hi = -kInf;
    for (size_t i = 0; i < n; ++i) {
      range_lo = std::min(range_lo, lo[i]);
      range_hi = std::max(range_hi, hi[i]);
    }
    if (!(range_hi > range_lo)) return;
    if (n <= size_t(config_.bins)) {
      exact_candidates(lo, hi, n, n, d, nl, nr);
    } else {
      binned_candidates(lo, hi, n, range_lo, range_hi, s, d, nl, nr);
    }
    // A large node (axes only) also tries the extent planes of the triangles the autopartition would
    // take: at a fan's centre every triangle ends at the shared vertex, and only a plane through it
    // separates them (without it, 20k `fan`'s centre stayed one leaf of 20,000).
    if (large_node(n)) exact_candidates(lo, hi, n, size_t(config_.autopartition), d, nl, nr);
    float cell_lo, cell_hi;
    surface.extent(dir, cell_lo, cell_hi);
    const float min_gap = (cell_hi - cell_lo) / float(config_.bins);
    size_t m = 0;  // the planes kept, moved to the front before their areas are computed
    for (size_t j = 0; j < d.size(); ++j) {
      if (nl[j] == 0 && !(d[j] - cell_lo >= min_gap)) continue;
      if (nr[j] == 0 && !(cell_hi - d[j] >= min_gap)) continue;
      d[m] = d[j];
      nl[m] = nl[j];
      nr[m++] = nr[j];
    }
    grow_buffer(al, m);
    grow_buffer(ar, m);
    surface.areas(dir, std::span<const float>(d.data(), m), al.data(), ar.data());
    for (size_t j = 0; j < m; ++j)
      keep(ch, BspPlane{dir, d[j]}, cell_area, al[j], ar[j], nl[j], nr[j], n, shave_ok);
  }

  /// Planes at the start and end of the extents of `samples` primitives spread over the node (every one
  /// when samples >= n; that primitive on one side only), appended with exact counts.
  void exact_candidates(const float* lo, const float* hi, size_t n, size_t samples, std::vector<float>& d,
                        std::vector<uint32_t>& nl, std::vector<uint32_t>& nr) const {
    using F = float __attribute__((vector_size(kCountLanes * sizeof(float))));
    using I = int32_t __attribute__((vector_size(kCountLanes * sizeof(int32_t))));
    const size_t k = std::min(n, samples), count = 2 * k;
    const size_t padded = (count + kCountLanes - 1) / kCountLanes * kCountLanes;
    thread_local std::vector<float> x;  // used only here: no call below builds a node
    thread_local std::vector<uint32_t> l, r;
    grow_buffer(x, padded);  // kept buffers filled in place (assign was a call per node that rarely grew)
    grow_buffer(l, padded);
    grow_buffer(r, padded);
    for (size_t j = 0; j < k; ++j) {
      const size_t i = k == n ? j : j * n / k;  // (no integer division per plane when every one is tried)
      x[2 * j] = lo[i];                         // primitive i above only (side_bits)
      x[2 * j + 1] = hi[i];                     // primitive i below only
    }
    std::fill(x.begin() + ptrdiff_t(count), x.begin() + ptrdiff_t(padded), 0.0f);
    // The planes kCountLanes at a time, primitive after primitive: sides_of's operations per lane, the
    // counts in registers (as arrays in memory, most of the time went to their loads and stores).
    const F half = 0.5f * margin_ - F{}, zero = F{};
    for (size_t c = 0; c < padded; c += kCountLanes) {
      F at;
      std::memcpy(&at, &x[c], sizeof(F));
      I below = {}, above = {};
      for (size_t i = 0; i < n; ++i) {
        const F a = lo[i] - at, b = hi[i] - at;
        const I below_band = b <= half, above_band = a >= -half, middle_above = a + b > zero;
        below -= ~above_band | (below_band & ~middle_above);  // a true comparison is -1
        above -= ~below_band | (above_band & middle_above);
      }
      std::memcpy(&l[c], &below, sizeof(I));
      std::memcpy(&r[c], &above, sizeof(I));
    }
    d.insert(d.end(), x.begin(), x.begin() + ptrdiff_t(count));
    nl.insert(nl.end(), l.begin(), l.begin() + ptrdiff_t(count));
    nr.insert(nr.end(), r.begin(), r.begin() + ptrdiff_t(count));
  }
  /// Planes exact_candidates counts at once: a vector of the target's (CellSurface::kChunk; 16 on an AVX2
  /// target padded a small node's few planes to two vectors).
  static constexpr size_t kCountLanes = CellSurface::kChunk;

  /// The bin boundaries and the planes two margins outside the whole range, with binned counts.
  void binned_candidates(const float* lo, const float* hi, size_t n, float range_lo, float range_hi,
                         PlaneScratch& s, std::vector<float>& d, std::vector<uint32_t>& nl,
                         std::vector<uint32_t>& nr) const {
    const int bins = config_.bins;
    std::vector<uint32_t>&starts = s.starts, &ends = s.ends;
    grow_buffer(starts, size_t(bins));
    grow_buffer(ends, size_t(bins));
    std::fill_n(starts.begin(), bins, 0u);
    std::fill_n(ends.begin(), bins, 0u);
    const float scale = float(bins) / (range_hi - range_lo);
    for (size_t i = 0; i < n; ++i) {
      ++starts[std::clamp(int((lo[i] - range_lo) * scale), 0, bins - 1)];
      ++ends[std::clamp(int((hi[i] - range_lo) * scale), 0, bins - 1)];
    }
    d.push_back(range_lo - 2.0f * margin_);
    nl.push_back(0);
    nr.push_back(uint32_t(n));
    uint32_t l = 0, r = uint32_t(n);
    for (int j = 1; j < bins; ++j) {
      l += starts[j - 1];
      r -= ends[j - 1];
      d.push_back(range_lo + (range_hi - range_lo) * float(j) / float(bins));
      nl.push_back(l);
      nr.push_back(r);
    }
    d.push_back(range_hi + 2.0f * margin_);
    nl.push_back(uint32_t(n));
    nr.push_back(0);
  }

  /// The sides of a part spanning signed distances [lo, hi] from a plane, without branches: below when it
  /// reaches more than `half` (half the margin) below the plane, above when more than that above, and a
  /// part within that band of the plane on both sides stays on one side only (as Wald and Havran place
  /// touching primitives; the traversal's band, margin plus rounding, covers it): the side of its middle.
  /// (It was always the below side: a part wholly above the plane, within the band, went below, where on an
  /// elongated mesh with a plane at a shallow angle to the long axis the child's cell lay far away along
  /// the plane, and the part was clipped away: an outside check's 4e4-long, 1e-3-thin triangles.)
  /// Written with bit operations on 0/1 values (below unless wholly within the above band or, within both
  /// bands, its middle above; above likewise), so the candidates' counting loops stay vectorized.
  [[gnu::always_inline]] static void sides_of(float lo, float hi, float half, uint32_t& below,
                                              uint32_t& above) {
    const uint32_t below_band = hi <= half, above_band = lo >= -half, middle_above = lo + hi > 0.0f;
    below = (above_band ^ 1u) | (below_band & (middle_above ^ 1u));
    above = (below_band ^ 1u) | (above_band & middle_above);
  }
  /// Side of a primitive whose clipped part spans signed distances [lo, hi] from a plane: bit 0 below, bit 1
  /// above (sides_of).
  int side_bits(float lo, float hi) const {
    uint32_t below, above;
    sides_of(lo, hi, 0.5f * margin_, below, above);
    return int(below | (above << 1));
  }
  /// Side bits of every primitive of the node against plane (side_bits), and the counts below and above.
  void classify(const NodePrims& np, const BspPlane& plane, std::vector<uint8_t>& sides, size_t& nl,
                size_t& nr) const {
    thread_local std::vector<float> dots, lo, hi;  // used only here: no call below builds a node
    grow_buffer(lo, np.size());
    grow_buffer(hi, np.size());
    ranges(np, plane.n, dots, lo.data(), hi.data());
    sides.resize(np.size());
    for (size_t k = 0; k < np.size(); ++k) {
      sides[k] = uint8_t(side_bits(lo[k] - plane.d, hi[k] - plane.d));
      nl += sides[k] & 1;
      nr += sides[k] >> 1;
    }
  }

  /// Nodes of at most this many primitives use their thread's kept candidate buffers (find_plane).
  static constexpr size_t kKeptScratchMax = 4096;
  /// Nodes at least this large build their children in parallel (BSP nodes are costly: split the work deep).
  static constexpr size_t kParallelMin = 256;
  /// Nodes of at least kParallelPrims primitives clip them and measure their ranges in parallel, in chunks
  /// of about kParallelGrain (collect, ranges).
  static constexpr size_t kParallelPrims = size_t(1) << 16, kParallelGrain = size_t(1) << 14;
  /// build_top's levels hold at most this many references (about 1.6 GB of clipped parts); more than the
  /// 200k hostile inputs' budget (6.4M), so a tree over it is abandoned in the breadth-first top. 2^25
  /// (2^23 until issue 11's twelfth step, when a 10M input's root went straight to the depth-first build:
  /// its top levels' nodes then ran one or two at a time, and every parallel node copied its above subtree
  /// into its parent's buffer; breadth first, a 10M ordinary input's levels hold 10-12M references).
  static constexpr size_t kTopRefs = size_t(1) << 25;
  /// build_top's levels hold at most kTopNodes nodes, or kTopNodesMax (and N) while each level holds more
  /// than kTopGrowth times the references of the one before: a tree over the budget passes it within its
  /// duplicating levels, and any other tree goes on depth first, with little memory (the same tree either
  /// way: these bounds only choose the order of the work). 200k `needles` copies 1.2x a level: with 1.25
  /// and 16,384 the top handed on at 2,048 nodes and the depth-first build made 7.3M nodes before the
  /// ledger passed the budget (32 s of 38); with 1.1 and 2^19 the top passes it at 114k nodes (7 s). At
  /// most N nodes a level: 20k `needles`, within the budget, copies 1.2x a level to its leaves, and its
  /// top held the whole tree (358 MB of build peak instead of 50).
  static constexpr size_t kTopNodes = 1024, kTopNodesMax = size_t(1) << 19;
  static constexpr double kTopGrowth = 1.1;
  const P& prims_;
  BspConfig config_;
  int depth_limit_;                      ///< resolved depth limit (> 0)
  float margin_;                         ///< insertion margin (from the root box)
  vec3 origin_;                          ///< the origin of the tree's frame, in world coordinates
  mutable RefLedger* ledger_ = nullptr;  ///< the unbudgeted attempt's ledger (build_with_budget)
  /// The first attempt's tree, during the second (memoized_decision).
  mutable const BspBuffer* memo_ = nullptr;
  mutable bool budget_exhausted_ = false;
  mutable float root_area_ = 0.0f;   ///< the root cell's surface area (set_gain_floor)
  mutable float gain_floor_ = 0.0f;  ///< min_gain / N (set_gain_floor; 0: the rule is off)
};

}  // namespace ab
