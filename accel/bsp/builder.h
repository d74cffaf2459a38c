// The BSP build with arbitrary split planes (Ize, Wald and Parker 2008, "Ray tracing with the BSP tree";
// Kammaje and Mora 2007): candidate planes (candidates.h) priced by the SAH over the node's convex cell
// (cell.h), and a conservative partition (a primitive within the insertion margin of the plane goes to both
// sides). Large nodes build their two subtrees in parallel, each into its own buffer, appended in a fixed
// order (the same tree for any thread count). The reference budget (build_with_budget, refine_rules.h) is
// the safety net of the references: at most ref_budget per primitive, the tree unchanged on any input whose
// tree stays under it.
#pragma once

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <type_traits>
#include <vector>

#include "accel/bsp/candidates.h"
#include "accel/bsp/cell.h"
#include "accel/bsp/config.h"
#include "accel/bsp/node.h"
#include "accel/common/refine_rules.h"
#include "accel/core/clip.h"

namespace ab {

/// Builds BSP trees over a primitive set P.
template <class P>
class BspBuilder {
 public:
  /// Builder over prims with the tree's configuration, its resolved depth limit and its insertion margin.
  BspBuilder(const P& prims, const BspConfig& config, int depth_limit, float margin)
      : prims_(prims), config_(config), depth_limit_(depth_limit), margin_(margin) {}

  /// Builds over ids (finite bounds) inside box into out.
  void build(std::vector<uint32_t> ids, const AABB& box, BspBuffer& out) const {
    auto attempt = [&](RefLedger* ledger, RefBudget budget) {
      ledger_ = ledger;
      out = BspBuffer{};
      build_node(std::vector<uint32_t>(ids), ConvexCell::from_box(box), {}, Depth{0, 0, budget}, out);
    };
    budget_exhausted_ = build_with_budget(ids.size(), config_.ref_budget, depth_limit_, attempt);
    ledger_ = nullptr;
  }
  /// True when the tree was built with the reference budget (build_with_budget).
  bool budget_exhausted() const { return budget_exhausted_; }

 private:
  struct Choice {
    BspPlane plane;
    float cost = kInf;
  };
  /// The node's primitives that reach its cell's (grown) bounding box, each with the support points of
  /// its part inside that box: classifying the clipped part, not the whole primitive, keeps long
  /// primitives from being duplicated into every cell their supporting line or plane crosses.
  struct NodePrims {
    std::vector<uint32_t> ids;
    std::vector<uint32_t> start{0};
    std::vector<vec3> pts;
    size_t size() const { return ids.size(); }
  };

  /// A half-space dot(n, x) <= offset bounding the cell (already grown by the margin).
  struct HalfSpace {
    vec3 n;
    float offset;
  };

  NodePrims gather(const std::vector<uint32_t>& ids, const ConvexCell& cell,
                   const std::vector<HalfSpace>& path) const {
    AABB box = cell.bounds();
    box = {box.lo - vec3(margin_), box.hi + vec3(margin_)};
    NodePrims np;
    vec3 buf[kMaxSupportPoints];
    for (uint32_t id : ids) {
      int k = support_points(prims_, id, box, buf);
      if constexpr (std::is_same_v<P, TrianglePrims>) k = clip_to_path(buf, k, path);
      if (k == 0) continue;
      np.ids.push_back(id);
      np.pts.insert(np.pts.end(), buf, buf + k);
      np.start.push_back(uint32_t(np.pts.size()));
    }
    return np;
  }

  /// Clips a triangle's polygon by the oblique half-spaces of the path (the box took care of the axes).
  /// Stops clipping (keeping a superset) before the polygon could outgrow its fixed capacity.
  static int clip_to_path(vec3* pts, int k, const std::vector<HalfSpace>& path) {
    if (k == 0 || path.empty()) return k;
    ClipPolygon poly;
    std::copy(pts, pts + k, poly.v.begin());
    poly.n = k;
    for (const HalfSpace& h : path) {
      if (poly.n == 0 || poly.n + 2 >= int(poly.v.size())) break;
      clip_polygon(poly, h.n, h.offset);
    }
    std::copy(poly.v.begin(), poly.v.begin() + poly.n, pts);
    return poly.n;
  }

  /// Depth of a node: all levels, and the splits with primitives on both sides. A split with an empty side
  /// (cutting off empty space, often a corner of the cell by an oblique plane) never puts an entry on the
  /// traversal stack, so only the other splits count against max_depth; the levels have their own bound.
  /// With the node's reference budget.
  struct Depth {
    int levels = 0, splits = 0;
    RefBudget budget;
  };
  static constexpr int kEmptyCutLevels = 32;

  void build_node(std::vector<uint32_t>&& ids, const ConvexCell& cell, const std::vector<HalfSpace>& path,
                  Depth depth, BspBuffer& out) const {
    if (ledger_ && ledger_->over()) return;  // an abandoned attempt
    NodePrims np = gather(ids, cell, path);
    std::vector<uint32_t>().swap(ids);
    const size_t n = np.size();
    Choice best;
    if (n > 1 && depth.splits < depth_limit_ && depth.levels < depth_limit_ + kEmptyCutLevels)
      best = find_plane(np, cell);
    std::vector<uint32_t> left, right;
    if (best.cost < config_.costs.leaf(n)) partition(np, best.plane, left, right);
    if ((left.empty() && right.empty()) || (left.size() == n && right.size() == n) ||
        !depth.budget.allows(left.size() + right.size())) {
      if (ledger_) ledger_->add_leaf(n);
      out.nodes.push_back(out.make_leaf(np.ids));
      return;
    }
    if (ledger_) ledger_->add_children(left.size() + right.size());
    np = NodePrims{};
    const ConvexCell lcell = cell.part(best.plane, true), rcell = cell.part(best.plane, false);
    std::vector<HalfSpace> lpath = path, rpath = path;
    if (is_oblique(best.plane)) {
      lpath.push_back({best.plane.n, best.plane.d + margin_});
      rpath.push_back({-best.plane.n, -best.plane.d + margin_});
    }
    const int levels = depth.levels + 1, splits = depth.splits + int(!left.empty() && !right.empty());
    const size_t all = left.size() + right.size();
    const Depth lnext{levels, splits, depth.budget.share(left.size(), all)};
    const Depth rnext{levels, splits, depth.budget.share(right.size(), all)};
    const size_t self = out.nodes.size();
    const uint32_t plane = uint32_t(out.payload.size());
    out.payload.push_back(best.plane);
    out.nodes.push_back(BspNode::leaf(0, 0));
    if (n >= kParallelMin) {
      BspBuffer lb, rb;
      tbb::parallel_invoke([&] { build_node(std::move(left), lcell, lpath, lnext, lb); },
                           [&] { build_node(std::move(right), rcell, rpath, rnext, rb); });
      out.append(lb);
      out.nodes[self] = BspNode::interior(plane, uint32_t(out.nodes.size()));
      out.append(rb);
    } else {
      build_node(std::move(left), lcell, lpath, lnext, out);
      out.nodes[self] = BspNode::interior(plane, uint32_t(out.nodes.size()));
      build_node(std::move(right), rcell, rpath, rnext, out);
    }
  }

  /// Signed-distance range of primitive k's support points from plane (dir, d).
  static void range(const NodePrims& np, size_t k, const vec3& n, float d, float& lo, float& hi) {
    lo = kInf;
    hi = -kInf;
    for (uint32_t j = np.start[k]; j < np.start[k + 1]; ++j) {
      const float x = glm::dot(n, np.pts[j]) - d;
      lo = std::min(lo, x);
      hi = std::max(hi, x);
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

  Choice find_plane(const NodePrims& np, const ConvexCell& cell) const {
    Choice best;
    const CellSurface surface(cell);
    const float area = surface.area();
    if (!(area > 0.0f)) return best;
    const CellArea cell_area{area, 1.0f / area};
    for (const vec3& dir : bsp_directions()) binned_planes(np, surface, cell_area, dir, best);
    const size_t k = std::min<size_t>(np.size(), size_t(config_.autopartition));
    for (size_t j = 0; j < k; ++j) {
      BspPlane own;
      if (!supporting_plane(prims_, np.ids[j * np.size() / k], own)) continue;
      // The plane itself and the plane moved two margins to either side, which puts the primitives
      // lying in it on one side only (like the planar events of Wald and Havran 2006).
      const float d[3] = {own.d, own.d - 2.0f * margin_, own.d + 2.0f * margin_};
      float al[3], ar[3];
      surface.areas(own.n, d, al, ar);
      for (int m = 0; m < 3; ++m) {
        const BspPlane plane{own.n, d[m]};
        size_t nl = 0, nr = 0;
        for (size_t i = 0; i < np.size(); ++i) {
          const int s = side(np, i, plane);
          nl += s & 1;
          nr += s >> 1;
        }
        const float c = cost(cell_area, al[m], ar[m], nl, nr);
        if (c < best.cost) best = {plane, c};
      }
    }
    return best;
  }

  /// Candidate planes of direction dir. A node of at most `bins` primitives tries the planes at the ends of
  /// each primitive's extent (the primitive is classified on one side only), like the events of a k-d sweep;
  /// a larger node the bin boundaries of the extents (Wald 2007's binning, a primitive counted on every side
  /// its extent reaches) and two planes just outside all extents. A plane with an empty side must cut off at
  /// least 1/bins of the cell's extent, or each node would shave off another sliver (its primitives clipped a
  /// little tighter) down to the depth limit.
  void binned_planes(const NodePrims& np, const CellSurface& surface, const CellArea& cell_area,
                     const vec3& dir, Choice& best) const {
    const size_t n = np.size();
    std::vector<float> lo(n), hi(n);
    float range_lo = kInf, range_hi = -kInf;
    for (size_t i = 0; i < n; ++i) {
      range(np, i, dir, 0.0f, lo[i], hi[i]);
      range_lo = std::min(range_lo, lo[i]);
      range_hi = std::max(range_hi, hi[i]);
    }
    if (!(range_hi > range_lo)) return;
    std::vector<float> d;
    std::vector<uint32_t> nl, nr;
    if (n <= size_t(config_.bins)) {
      exact_candidates(lo, hi, d, nl, nr);
    } else {
      binned_candidates(lo, hi, range_lo, range_hi, d, nl, nr);
    }
    float cell_lo, cell_hi;
    surface.extent(dir, cell_lo, cell_hi);
    const float min_gap = (cell_hi - cell_lo) / float(config_.bins);
    std::vector<float> al(d.size()), ar(d.size());
    surface.areas(dir, d, al.data(), ar.data());
    for (size_t j = 0; j < d.size(); ++j) {
      if (nl[j] == 0 && !(d[j] - cell_lo >= min_gap)) continue;
      if (nr[j] == 0 && !(cell_hi - d[j] >= min_gap)) continue;
      const float c = cost(cell_area, al[j], ar[j], nl[j], nr[j]);
      if (c < best.cost) best = {BspPlane{dir, d[j]}, c};
    }
  }

  /// Planes at each extent's start and end (that primitive on one side only), with exact counts.
  void exact_candidates(const std::vector<float>& lo, const std::vector<float>& hi, std::vector<float>& d,
                        std::vector<uint32_t>& nl, std::vector<uint32_t>& nr) const {
    for (size_t k = 0; k < lo.size(); ++k) {
      d.push_back(lo[k]);  // primitive k above only (side_bits)
      d.push_back(hi[k]);  // primitive k below only
    }
    for (const float x : d) {
      uint32_t l = 0, r = 0;
      for (size_t k = 0; k < lo.size(); ++k) {  // the classification of side()
        const int bits = side_bits(lo[k] - x, hi[k] - x);
        l += bits & 1;
        r += bits >> 1;
      }
      nl.push_back(l);
      nr.push_back(r);
    }
  }

  /// The bin boundaries and the planes two margins outside the whole range, with binned counts.
  void binned_candidates(const std::vector<float>& lo, const std::vector<float>& hi, float range_lo,
                         float range_hi, std::vector<float>& d, std::vector<uint32_t>& nl,
                         std::vector<uint32_t>& nr) const {
    const size_t n = lo.size();
    const int bins = config_.bins;
    std::vector<uint32_t> starts(bins, 0), ends(bins, 0);
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

  /// Side of a primitive whose clipped part spans signed distances [lo, hi] from a plane: bit 0 below, bit 1
  /// above. A part within half the margin of the plane on the other side stays on one side (as Wald and
  /// Havran place touching primitives): the traversal's band (margin plus rounding) covers it.
  int side_bits(float lo, float hi) const {
    if (hi <= 0.5f * margin_) return 1;
    if (lo >= -0.5f * margin_) return 2;
    return 3;
  }
  /// Side of primitive k (side_bits).
  int side(const NodePrims& np, size_t k, const BspPlane& plane) const {
    float lo, hi;
    range(np, k, plane.n, plane.d, lo, hi);
    return side_bits(lo, hi);
  }

  void partition(const NodePrims& np, const BspPlane& plane, std::vector<uint32_t>& left,
                 std::vector<uint32_t>& right) const {
    for (size_t k = 0; k < np.size(); ++k) {
      const int s = side(np, k, plane);
      if (s & 1) left.push_back(np.ids[k]);
      if (s & 2) right.push_back(np.ids[k]);
    }
  }

  /// Nodes at least this large build their children in parallel (BSP nodes are costly: split the work deep).
  static constexpr size_t kParallelMin = 256;
  const P& prims_;
  BspConfig config_;
  int depth_limit_;                      ///< resolved depth limit (> 0)
  float margin_;                         ///< insertion margin (from the root box)
  mutable RefLedger* ledger_ = nullptr;  ///< the unbudgeted attempt's ledger (build_with_budget)
  mutable bool budget_exhausted_ = false;
};

}  // namespace ab
