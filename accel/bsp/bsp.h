// BSP tree with arbitrary split planes (Ize, Wald and Parker 2008, "Ray tracing with the BSP tree";
// Kammaje and Mora 2007): candidate planes in bsp_candidates.h, their cost over the node's convex cell
// (bsp_cell.h), a conservative partition
// (a primitive within the insertion margin of the plane goes to both sides), and the same robust
// front-to-back stack traversal as the k-d trees with t_split = (d - n.o) / (n.dir).
#pragma once

#include "accel/core/box_test.h"
#include "accel/core/accelerator.h"
#include "accel/bsp/candidates.h"
#include "accel/bsp/cell.h"
#include "accel/common/spatial_tree.h"
#include "accel/core/params.h"
#include "accel/common/split_plane.h"

#include <tbb/parallel_invoke.h>

#include <memory>
#include <type_traits>
#include <string>
#include <vector>

namespace ab {

/// One BSP node (8 bytes): an interior node (index of its plane, index of the above child and a flag per
/// child that is an empty leaf; the below child, when not empty, follows it) or a leaf (offset and count
/// of its primitive indices). Empty children are flags, not nodes (drop_empty_leaves, kd_node.h).
class BspNode {
 public:
  /// A leaf of `count` primitive indices starting at `first`.
  static BspNode leaf(uint32_t first, uint32_t count) { return BspNode(first, (count << 1) | 1u); }
  /// An interior node split by plane `plane`, above child `above`.
  static BspNode interior(uint32_t plane, uint32_t above, bool below_empty = false, bool above_empty = false) {
    return BspNode(plane, (above << 3) | (uint32_t(above_empty) << 2) | (uint32_t(below_empty) << 1));
  }

  /// True for a leaf.
  bool is_leaf() const { return bits_ & 1u; }
  /// Plane index (interior nodes).
  uint32_t plane() const { return word_; }
  /// Above child (interior nodes); the below child is this node's index + 1.
  uint32_t above() const { return bits_ >> 3; }
  /// True when the below child is an empty leaf (interior nodes).
  bool below_empty() const { return (bits_ & 2u) != 0; }
  /// True when the above child is an empty leaf (interior nodes).
  bool above_empty() const { return (bits_ & 4u) != 0; }
  /// First primitive index (leaves).
  uint32_t first() const { return word_; }
  /// Primitive count (leaves).
  uint32_t count() const { return bits_ >> 1; }
  /// Moves the node by the given bases (splicing buffers).
  void rebase(uint32_t node_base, uint32_t prim_base, uint32_t plane_base) {
    if (is_leaf()) {
      word_ += prim_base;
    } else {
      word_ += plane_base;
      bits_ += node_base << 3;
    }
  }
  /// This interior node with another above child and empty-child flags (drop_empty_leaves).
  BspNode relinked(uint32_t above, bool below_empty, bool above_empty) const {
    return interior(plane(), above, below_empty, above_empty);
  }
  /// Largest node index an interior node can hold.
  static constexpr uint32_t kMaxIndex = (1u << 29) - 1;

 private:
  BspNode(uint32_t word, uint32_t bits) : word_(word), bits_(bits) {}
  uint32_t word_;
  uint32_t bits_;
};
static_assert(sizeof(BspNode) == 8);

/// Nodes, planes and primitive indices of a BSP tree (or a subtree under construction).
struct BspBuffer {
  std::vector<BspNode> nodes;
  std::vector<BspPlane> planes;
  std::vector<uint32_t> prims;

  /// Appends a subtree built into its own buffer.
  void append(const BspBuffer& sub) {
    const uint32_t nb = uint32_t(nodes.size()), pb = uint32_t(prims.size()), qb = uint32_t(planes.size());
    for (BspNode n : sub.nodes) {
      n.rebase(nb, pb, qb);
      nodes.push_back(n);
    }
    planes.insert(planes.end(), sub.planes.begin(), sub.planes.end());
    prims.insert(prims.end(), sub.prims.begin(), sub.prims.end());
  }
};

/// True when the plane's normal is not one of the three axes.
inline bool is_oblique(const BspPlane& p) { return !(p.n.x == 1.0f || p.n.y == 1.0f || p.n.z == 1.0f); }

/// Settings of the BSP builder.
struct BspSettings {
  float traversal_cost = 1.0f;
  float intersection_cost = 1.8f;  ///< measured on slivers: fewer triangles per ray at about the same nodes
  float empty_bonus = 0.05f;       ///< small: 13 directions offer many corner cuts, each one more level
  int bins = 16;             ///< plane positions per fixed direction: bins - 1
  int autopartition = 8;     ///< triangles whose supporting planes are tried per node
  int max_depth = 0;         ///< resolved depth limit
  float margin = 0.0f;       ///< insertion margin (from the root box)
};

/// Builds BSP trees over a primitive set P.
template <class P>
class BspBuilder {
 public:
  /// Builder over prims with settings s.
  BspBuilder(const P& prims, const BspSettings& s) : prims_(prims), s_(s) {}

  /// Builds over ids (finite bounds) inside box into out.
  void build(std::vector<uint32_t> ids, const AABB& box, BspBuffer& out) const {
    build_node(std::move(ids), ConvexCell::from_box(box), {}, Depth{}, out);
  }

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

  NodePrims gather(const std::vector<uint32_t>& ids, const ConvexCell& cell, const std::vector<HalfSpace>& path) const {
    AABB box = cell.bounds();
    box = {box.lo - vec3(s_.margin), box.hi + vec3(s_.margin)};
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
  struct Depth {
    int levels = 0, splits = 0;
  };
  static constexpr int kEmptyCutLevels = 32;

  void build_node(std::vector<uint32_t>&& ids, const ConvexCell& cell, const std::vector<HalfSpace>& path, Depth depth,
                  BspBuffer& out) const {
    NodePrims np = gather(ids, cell, path);
    std::vector<uint32_t>().swap(ids);
    const size_t n = np.size();
    Choice best;
    if (n > 1 && depth.splits < s_.max_depth && depth.levels < s_.max_depth + kEmptyCutLevels)
      best = find_plane(np, cell);
    std::vector<uint32_t> left, right;
    if (best.cost < s_.intersection_cost * float(n)) partition(np, best.plane, left, right);
    if ((left.empty() && right.empty()) || (left.size() == n && right.size() == n)) {
      out.nodes.push_back(BspNode::leaf(uint32_t(out.prims.size()), uint32_t(n)));
      out.prims.insert(out.prims.end(), np.ids.begin(), np.ids.end());
      return;
    }
    np = NodePrims{};
    const ConvexCell lcell = cell.part(best.plane, true), rcell = cell.part(best.plane, false);
    std::vector<HalfSpace> lpath = path, rpath = path;
    if (is_oblique(best.plane)) {
      lpath.push_back({best.plane.n, best.plane.d + s_.margin});
      rpath.push_back({-best.plane.n, -best.plane.d + s_.margin});
    }
    const Depth next{depth.levels + 1, depth.splits + int(!left.empty() && !right.empty())};
    const size_t self = out.nodes.size();
    const uint32_t plane = uint32_t(out.planes.size());
    out.planes.push_back(best.plane);
    out.nodes.push_back(BspNode::leaf(0, 0));
    if (n >= kParallelMin) {
      BspBuffer lb, rb;
      tbb::parallel_invoke([&] { build_node(std::move(left), lcell, lpath, next, lb); },
                           [&] { build_node(std::move(right), rcell, rpath, next, rb); });
      out.append(lb);
      out.nodes[self] = BspNode::interior(plane, uint32_t(out.nodes.size()));
      out.append(rb);
    } else {
      build_node(std::move(left), lcell, lpath, next, out);
      out.nodes[self] = BspNode::interior(plane, uint32_t(out.nodes.size()));
      build_node(std::move(right), rcell, rpath, next, out);
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

  /// SAH cost of a plane from the areas of the two parts and the counts on each side; infinite for a plane
  /// that does not cut the cell (a part without area), which would only earn the empty bonus and repeat
  /// itself down to the depth limit.
  float cost(float inv_area, float al, float ar, size_t nl, size_t nr) const {
    if (!(std::min(al, ar) * inv_area > 1e-5f)) return kInf;
    const float lambda = (nl == 0 || nr == 0) ? 1.0f - s_.empty_bonus : 1.0f;
    return lambda * (s_.traversal_cost + s_.intersection_cost * inv_area * (al * float(nl) + ar * float(nr)));
  }

  Choice find_plane(const NodePrims& np, const ConvexCell& cell) const {
    Choice best;
    const CellSurface surface(cell);
    const float area = surface.area();
    if (!(area > 0.0f)) return best;
    const float inv_area = 1.0f / area;
    for (const vec3& dir : bsp_directions()) binned_planes(np, surface, inv_area, dir, best);
    const size_t k = std::min<size_t>(np.size(), size_t(s_.autopartition));
    for (size_t j = 0; j < k; ++j) {
      BspPlane own;
      if (!supporting_plane(prims_, np.ids[j * np.size() / k], own)) continue;
      // The plane itself and the plane moved two margins to either side, which puts the primitives
      // lying in it on one side only (like the planar events of Wald and Havran 2006).
      const float d[3] = {own.d, own.d - 2.0f * s_.margin, own.d + 2.0f * s_.margin};
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
        const float c = cost(inv_area, al[m], ar[m], nl, nr);
        if (c < best.cost) best = {plane, c};
      }
    }
    return best;
  }

  /// Candidate planes of direction dir. A node of at most `bins` primitives tries the planes at the ends of
  /// each primitive's extent (the primitive is classified on one side only), like the events of a k-d sweep; a larger node the bin boundaries of the extents (Wald 2007's binning, a primitive
  /// counted on every side its extent reaches) and two planes just outside all extents. A plane with an
  /// empty side must cut off at least 1/bins of the cell's extent, or each node would shave off another
  /// sliver (its primitives clipped a little tighter) down to the depth limit.
  void binned_planes(const NodePrims& np, const CellSurface& surface, float inv_area, const vec3& dir,
                     Choice& best) const {
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
    if (n <= size_t(s_.bins)) {
      exact_candidates(lo, hi, d, nl, nr);
    } else {
      binned_candidates(lo, hi, range_lo, range_hi, d, nl, nr);
    }
    float cell_lo, cell_hi;
    surface.extent(dir, cell_lo, cell_hi);
    const float min_gap = (cell_hi - cell_lo) / float(s_.bins);
    std::vector<float> al(d.size()), ar(d.size());
    surface.areas(dir, d, al.data(), ar.data());
    for (size_t j = 0; j < d.size(); ++j) {
      if (nl[j] == 0 && !(d[j] - cell_lo >= min_gap)) continue;
      if (nr[j] == 0 && !(cell_hi - d[j] >= min_gap)) continue;
      const float c = cost(inv_area, al[j], ar[j], nl[j], nr[j]);
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
  void binned_candidates(const std::vector<float>& lo, const std::vector<float>& hi, float range_lo, float range_hi,
                         std::vector<float>& d, std::vector<uint32_t>& nl, std::vector<uint32_t>& nr) const {
    const size_t n = lo.size();
    const int bins = s_.bins;
    std::vector<uint32_t> starts(bins, 0), ends(bins, 0);
    const float scale = float(bins) / (range_hi - range_lo);
    for (size_t i = 0; i < n; ++i) {
      ++starts[std::clamp(int((lo[i] - range_lo) * scale), 0, bins - 1)];
      ++ends[std::clamp(int((hi[i] - range_lo) * scale), 0, bins - 1)];
    }
    d.push_back(range_lo - 2.0f * s_.margin);
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
    d.push_back(range_hi + 2.0f * s_.margin);
    nl.push_back(uint32_t(n));
    nr.push_back(0);
  }

  /// Side of a primitive whose clipped part spans signed distances [lo, hi] from a plane: bit 0 below, bit 1
  /// above. A part within half the margin of the plane on the other side stays on one side (as Wald and
  /// Havran place touching primitives): the traversal's band (margin plus rounding) covers it.
  int side_bits(float lo, float hi) const {
    if (hi <= 0.5f * s_.margin) return 1;
    if (lo >= -0.5f * s_.margin) return 2;
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

  static constexpr size_t kParallelMin = 256;  // BSP nodes are costly: split the work deep
  const P& prims_;
  BspSettings s_;
};

/// BSP tree (registry name bsp).
template <class P>
class BspTree final : public SpatialTreeQueries<BspTree<P>> {
  friend class SpatialTreeQueries<BspTree<P>>;

 public:
  /// Reads the configuration from params.
  BspTree(std::shared_ptr<const P> prims, Params& params) : prims_(std::move(prims)) {
    s_.traversal_cost = float(params.get_float("traversal_cost", 1.0, 1e-3, 1e6));
    s_.intersection_cost = float(params.get_float("intersection_cost", 1.8, 1e-3, 1e6));
    s_.empty_bonus = float(params.get_float("empty_bonus", 0.05, 0.0, 0.99));
    s_.bins = int(params.get_int("bins", 16, 2, 256));
    s_.autopartition = int(params.get_int("autopartition", 8, 0, 1024));
    max_depth_ = int(params.get_int("max_depth", 0, 0, 100));
    leaf_copies_ = read_leaf_copies(params);
    config_ = params.effective();
  }

  std::string name() const override { return "bsp"; }
  nlohmann::json config() const override { return config_; }
  AABB bounds() const override { return prims_->bounds(); }

 protected:
  void do_build() override {
    std::vector<uint32_t> ids = partition_finite(*prims_, unbounded_, box_);
    BspSettings s = s_;
    s.max_depth = max_depth_ > 0 ? max_depth_ : auto_kd_depth(ids.size());
    s.margin = ids.empty() ? 0.0f : insertion_margin(box_);
    margin_ = s.margin;
    BspBuffer out;
    if (!ids.empty()) BspBuilder<P>(*prims_, s).build(std::move(ids), box_, out);
    drop_empty_leaves(out.nodes);
    nodes_ = std::move(out.nodes);
    planes_ = std::move(out.planes);
    leaves_.assign(*prims_, std::move(out.prims), leaf_copies_);
    fill_stats(s.max_depth);
  }

 private:
  struct StackItem {
    uint32_t node;
    float t0, t1;
  };
  static constexpr int kStackSize = 128;  // one entry per split with both sides non-empty (max_depth <= 100)

  template <bool kCount, class Leaf, class BestT>
  [[gnu::always_inline]] bool traverse(const Ray& ray, RayCounters& c, Leaf&& leaf, BestT&& best_t) const {
    float t0 = ray.tmin, t1 = ray.tmax;
    if (nodes_.empty() || !slab_test(box_, RayBoxData(ray), t0, t1)) return false;
    const vec3 abs_org = glm::abs(ray.org);
    StackItem stack[kStackSize];
    int sp = 0;
    StackItem cur{0, t0, t1};
    while (true) {
      const BspNode& n = nodes_[cur.node];
      if constexpr (kCount) ++c.nodes;
      if (n.is_leaf()) {
        if constexpr (kCount) ++c.leaves;
        if (n.count() && leaf(n.first(), n.count())) return true;
      } else if (step(n, cur, ray, abs_org, stack, sp)) {
        continue;
      }
      if (!pop(stack, sp, best_t(), cur)) return false;
    }
  }

  /// One interior node: the plane step with a band that covers the rounding of n.o - d and the margin.
  [[gnu::always_inline]] bool step(const BspNode& n, StackItem& cur, const Ray& ray, const vec3& abs_org, StackItem* stack, int& sp) const {
    const BspPlane& p = planes_[n.plane()];
    const float org_dist = p.distance(ray.org);
    const float rate = glm::dot(p.n, ray.dir);
    const float band = margin_ + (std::fabs(p.d) + glm::dot(glm::abs(p.n), abs_org)) * 0x1p-20f;
    const float t_split = -org_dist / rate;
    const float widen = band / std::fabs(rate) + std::fabs(t_split) * kBoxEps;
    const PlaneVisit v = split_interval(org_dist, rate, t_split, widen, band, cur.t0, cur.t1);
    const uint32_t below = cur.node + 1, above = n.above();
    const uint32_t first = v.first_below ? below : above, second = v.first_below ? above : below;
    const bool visit_first = v.visit_first && !(v.first_below ? n.below_empty() : n.above_empty());
    const bool visit_second = v.visit_second && !(v.first_below ? n.above_empty() : n.below_empty());
    if (visit_first) {
      if (visit_second) stack[sp++] = {second, v.second_t0, cur.t1};
      cur = {first, cur.t0, v.first_t1};
      return true;
    }
    if (visit_second) {
      cur = {second, v.second_t0, cur.t1};
      return true;
    }
    return false;
  }

  [[gnu::always_inline]] static bool pop(const StackItem* stack, int& sp, float best_t, StackItem& cur) {
    while (sp > 0) {
      const StackItem& it = stack[--sp];
      if (it.t0 > best_t) continue;
      cur = it;
      return true;
    }
    return false;
  }

  void fill_stats(int depth_limit) {
    BuildStats& st = this->stats_;
    st = BuildStats{};
    st.primitives = prims_->size();
    st.nodes = nodes_.size();
    st.bytes = nodes_.size() * sizeof(BspNode) + planes_.size() * sizeof(BspPlane) + leaves_.bytes() +
               unbounded_.size() * 4;
    st.extra["depth_limit"] = depth_limit;
    st.extra["unbounded_primitives"] = unbounded_.size();
    st.extra["leaf_copies"] = leaves_.copied();
    size_t axis_planes = 0;
    for (const BspPlane& p : planes_) axis_planes += !is_oblique(p);
    st.extra["axis_aligned_planes"] = axis_planes;
    st.extra["oblique_planes"] = planes_.size() - axis_planes;
    std::vector<std::pair<uint32_t, uint32_t>> todo;
    if (!nodes_.empty()) todo.push_back({0, 0});
    while (!todo.empty()) {
      const auto [i, depth] = todo.back();
      todo.pop_back();
      const BspNode& n = nodes_[i];
      if (n.is_leaf()) {
        st.add_leaf(n.count(), depth);
        continue;
      }
      if (n.above_empty()) st.add_leaf(0, depth + 1);
      else todo.push_back({n.above(), depth + 1});
      if (n.below_empty()) st.add_leaf(0, depth + 1);
      else todo.push_back({i + 1, depth + 1});
    }
    st.extra["stored_nodes"] = nodes_.size();  // nodes: also the empty leaves, which are flags, not nodes
    if (st.leaves > 0) st.nodes = 2 * st.leaves - 1;
  }

  std::shared_ptr<const P> prims_;
  BspSettings s_;
  int max_depth_ = 0;
  LeafCopies leaf_copies_ = LeafCopies::kAuto;  ///< copy triangles into leaf order (LeafRefs)
  float margin_ = 0.0f;
  nlohmann::json config_;
  AABB box_;
  std::vector<BspNode> nodes_;
  std::vector<BspPlane> planes_;
  LeafRefs<P> leaves_;
  std::vector<uint32_t> unbounded_;
};

}  // namespace ab
