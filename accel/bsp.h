// BSP tree with arbitrary split planes (Ize, Wald and Parker 2008, "Ray tracing with the BSP tree";
// Kammaje and Mora 2007): candidate planes in bsp_candidates.h, their cost over the node's convex cell
// (bsp_cell.h), a conservative partition
// (a primitive within the insertion margin of the plane goes to both sides), and the same robust
// front-to-back stack traversal as the k-d trees with t_split = (d - n.o) / (n.dir).
#pragma once

#include "accel/accelerator.h"
#include "accel/bsp_candidates.h"
#include "accel/bsp_cell.h"
#include "accel/kd_node.h"
#include "accel/params.h"
#include "accel/split_plane.h"

#include <tbb/parallel_invoke.h>

#include <memory>
#include <type_traits>
#include <string>
#include <vector>

namespace ab {

/// One BSP node (8 bytes): an interior node (index of its plane, index of the above child; the below
/// child follows it) or a leaf (offset and count of its primitive indices).
class BspNode {
 public:
  /// A leaf of `count` primitive indices starting at `first`.
  static BspNode leaf(uint32_t first, uint32_t count) { return BspNode(first, (count << 1) | 1u); }
  /// An interior node split by plane `plane`, above child `above`.
  static BspNode interior(uint32_t plane, uint32_t above) { return BspNode(plane, above << 1); }

  /// True for a leaf.
  bool is_leaf() const { return bits_ & 1u; }
  /// Plane index (interior) or first primitive index (leaf).
  uint32_t first() const { return word_; }
  /// Above child (interior) or primitive count (leaf).
  uint32_t second() const { return bits_ >> 1; }
  /// Moves the node by the given bases (splicing buffers).
  void rebase(uint32_t node_base, uint32_t prim_base, uint32_t plane_base) {
    if (is_leaf()) {
      word_ += prim_base;
    } else {
      word_ += plane_base;
      bits_ += node_base << 1;
    }
  }

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
  float intersection_cost = 1.5f;
  float empty_bonus = 0.2f;
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
    build_node(std::move(ids), ConvexCell::from_box(box), {}, 0, out);
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

  void build_node(std::vector<uint32_t>&& ids, const ConvexCell& cell, const std::vector<HalfSpace>& path, int depth,
                  BspBuffer& out) const {
    NodePrims np = gather(ids, cell, path);
    std::vector<uint32_t>().swap(ids);
    const size_t n = np.size();
    Choice best;
    if (n > 1 && depth < s_.max_depth) best = find_plane(np, cell);
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
    const size_t self = out.nodes.size();
    const uint32_t plane = uint32_t(out.planes.size());
    out.planes.push_back(best.plane);
    out.nodes.push_back(BspNode::leaf(0, 0));
    if (n >= kParallelMin) {
      BspBuffer lb, rb;
      tbb::parallel_invoke([&] { build_node(std::move(left), lcell, lpath, depth + 1, lb); },
                           [&] { build_node(std::move(right), rcell, rpath, depth + 1, rb); });
      out.append(lb);
      out.nodes[self] = BspNode::interior(plane, uint32_t(out.nodes.size()));
      out.append(rb);
    } else {
      build_node(std::move(left), lcell, lpath, depth + 1, out);
      out.nodes[self] = BspNode::interior(plane, uint32_t(out.nodes.size()));
      build_node(std::move(right), rcell, rpath, depth + 1, out);
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

  float cost(const ConvexCell& cell, float inv_area, const BspPlane& plane, size_t nl, size_t nr) const {
    float al = 0.0f, ar = 0.0f;
    cell.areas(plane, al, ar);
    const float lambda = (nl == 0 || nr == 0) ? 1.0f - s_.empty_bonus : 1.0f;
    return lambda * (s_.traversal_cost + s_.intersection_cost * inv_area * (al * float(nl) + ar * float(nr)));
  }

  Choice find_plane(const NodePrims& np, const ConvexCell& cell) const {
    Choice best;
    const float area = cell.area();
    if (!(area > 0.0f)) return best;
    const float inv_area = 1.0f / area;
    for (const vec3& dir : bsp_directions()) binned_planes(np, cell, inv_area, dir, best);
    const size_t k = std::min<size_t>(np.size(), size_t(s_.autopartition));
    for (size_t j = 0; j < k; ++j) {
      BspPlane own;
      if (!supporting_plane(prims_, np.ids[j * np.size() / k], own)) continue;
      // The plane itself and the plane moved two margins to either side, which puts the primitives
      // lying in it on one side only (like the planar events of Wald and Havran 2006).
      for (float shift : {0.0f, -2.0f * s_.margin, 2.0f * s_.margin}) {
        const BspPlane plane{own.n, own.d + shift};
        size_t nl = 0, nr = 0;
        for (size_t i = 0; i < np.size(); ++i) {
          const int s = side(np, i, plane);
          nl += s & 1;
          nr += s >> 1;
        }
        const float c = cost(cell, inv_area, plane, nl, nr);
        if (c < best.cost) best = {plane, c};
      }
    }
    return best;
  }

  /// Planes of direction dir at the bin boundaries of the clipped primitives' extents (Wald 2007's
  /// binning, a primitive counted on every side its extent reaches).
  void binned_planes(const NodePrims& np, const ConvexCell& cell, float inv_area, const vec3& dir,
                     Choice& best) const {
    const size_t n = np.size();
    const int bins = int(std::min<size_t>(size_t(s_.bins), n + 1));
    std::vector<float> lo(n), hi(n);
    float range_lo = kInf, range_hi = -kInf;
    for (size_t i = 0; i < n; ++i) {
      range(np, i, dir, 0.0f, lo[i], hi[i]);
      range_lo = std::min(range_lo, lo[i]);
      range_hi = std::max(range_hi, hi[i]);
    }
    if (!(range_hi > range_lo)) return;
    std::vector<uint32_t> starts(bins, 0), ends(bins, 0);
    const float scale = float(bins) / (range_hi - range_lo);
    for (size_t i = 0; i < n; ++i) {
      ++starts[std::clamp(int((lo[i] - range_lo) * scale), 0, bins - 1)];
      ++ends[std::clamp(int((hi[i] - range_lo) * scale), 0, bins - 1)];
    }
    size_t nl = 0, nr = n;
    for (int j = 1; j < bins; ++j) {
      nl += starts[j - 1];
      nr -= ends[j - 1];
      const BspPlane plane{dir, range_lo + (range_hi - range_lo) * float(j) / float(bins)};
      const float c = cost(cell, inv_area, plane, nl, nr);
      if (c < best.cost) best = {plane, c};
    }
  }

  /// Side of primitive k: bit 0 below, bit 1 above (both when its clipped part comes within the margin).
  int side(const NodePrims& np, size_t k, const BspPlane& plane) const {
    float lo, hi;
    range(np, k, plane.n, plane.d, lo, hi);
    return (lo <= s_.margin ? 1 : 0) | (hi >= -s_.margin ? 2 : 0);
  }

  void partition(const NodePrims& np, const BspPlane& plane, std::vector<uint32_t>& left,
                 std::vector<uint32_t>& right) const {
    for (size_t k = 0; k < np.size(); ++k) {
      const int s = side(np, k, plane);
      if (s & 1) left.push_back(np.ids[k]);
      if (s & 2) right.push_back(np.ids[k]);
    }
  }

  static constexpr size_t kParallelMin = 8192;
  const P& prims_;
  BspSettings s_;
};

/// BSP tree (registry name bsp).
template <class P>
class BspTree final : public AcceleratorBase<BspTree<P>> {
 public:
  /// Reads the configuration from params.
  BspTree(std::shared_ptr<const P> prims, Params& params) : prims_(std::move(prims)) {
    s_.traversal_cost = float(params.get_float("traversal_cost", 1.0, 1e-3, 1e6));
    s_.intersection_cost = float(params.get_float("intersection_cost", 1.5, 1e-3, 1e6));
    s_.empty_bonus = float(params.get_float("empty_bonus", 0.2, 0.0, 0.99));
    s_.bins = int(params.get_int("bins", 16, 2, 256));
    s_.autopartition = int(params.get_int("autopartition", 8, 0, 1024));
    max_depth_ = int(params.get_int("max_depth", 0, 0, 100));
    config_ = params.effective();
  }

  std::string name() const override { return "bsp"; }
  nlohmann::json config() const override { return config_; }
  AABB bounds() const override { return prims_->bounds(); }

  /// Closest hit, front to back.
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    intersect_id_list<kCount>(*prims_, unbounded_.data(), uint32_t(unbounded_.size()), ray, best, inst, c);
    auto leaf = [&](const BspNode& n) {
      intersect_id_list<kCount>(*prims_, &ids_[n.first()], n.second(), ray, best, inst, c);
      return false;
    };
    traverse<kCount>(ray, c, leaf, [&] { return best.t; });
  }

  /// Any hit.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    if (occluded_id_list<kCount>(*prims_, unbounded_.data(), uint32_t(unbounded_.size()), ray, c)) return true;
    auto leaf = [&](const BspNode& n) { return occluded_id_list<kCount>(*prims_, &ids_[n.first()], n.second(), ray, c); };
    return traverse<kCount>(ray, c, leaf, [] { return kInf; });
  }

 protected:
  void do_build() override {
    std::vector<uint32_t> ids = partition_finite(*prims_, unbounded_, box_);
    BspSettings s = s_;
    s.max_depth = max_depth_ > 0 ? max_depth_ : auto_kd_depth(ids.size());
    s.margin = ids.empty() ? 0.0f : insertion_margin(box_);
    margin_ = s.margin;
    BspBuffer out;
    if (!ids.empty()) BspBuilder<P>(*prims_, s).build(std::move(ids), box_, out);
    nodes_ = std::move(out.nodes);
    planes_ = std::move(out.planes);
    ids_ = std::move(out.prims);
    fill_stats(s.max_depth);
  }

 private:
  struct StackItem {
    uint32_t node;
    float t0, t1;
  };
  static constexpr int kStackSize = 128;

  template <bool kCount, class Leaf, class BestT>
  bool traverse(const Ray& ray, RayCounters& c, Leaf&& leaf, BestT&& best_t) const {
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
        if (n.second() && leaf(n)) return true;
      } else if (step(n, cur, ray, abs_org, stack, sp)) {
        continue;
      }
      if (!pop(stack, sp, best_t(), cur)) return false;
    }
  }

  /// One interior node: the plane step with a band that covers the rounding of n.o - d and the margin.
  [[gnu::always_inline]] bool step(const BspNode& n, StackItem& cur, const Ray& ray, const vec3& abs_org, StackItem* stack, int& sp) const {
    const BspPlane& p = planes_[n.first()];
    const float org_dist = p.distance(ray.org);
    const float rate = glm::dot(p.n, ray.dir);
    const float band = margin_ + (std::fabs(p.d) + glm::dot(glm::abs(p.n), abs_org)) * 0x1p-20f;
    const float t_split = -org_dist / rate;
    const float widen = band / std::fabs(rate) + std::fabs(t_split) * kBoxEps;
    const PlaneVisit v = split_interval(org_dist, rate, t_split, widen, band, cur.t0, cur.t1);
    const uint32_t below = cur.node + 1, above = n.second();
    const uint32_t first = v.first_below ? below : above, second = v.first_below ? above : below;
    if (v.visit_first) {
      if (v.visit_second) stack[sp++] = {second, v.second_t0, cur.t1};
      cur = {first, cur.t0, v.first_t1};
      return true;
    }
    if (v.visit_second) {
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
    st.bytes = nodes_.size() * sizeof(BspNode) + planes_.size() * sizeof(BspPlane) + ids_.size() * 4 +
               unbounded_.size() * 4;
    st.extra["depth_limit"] = depth_limit;
    st.extra["unbounded_primitives"] = unbounded_.size();
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
        st.add_leaf(n.second(), depth);
        continue;
      }
      todo.push_back({n.second(), depth + 1});
      todo.push_back({i + 1, depth + 1});
    }
  }

  std::shared_ptr<const P> prims_;
  BspSettings s_;
  int max_depth_ = 0;
  float margin_ = 0.0f;
  nlohmann::json config_;
  AABB box_;
  std::vector<BspNode> nodes_;
  std::vector<BspPlane> planes_;
  std::vector<uint32_t> ids_;
  std::vector<uint32_t> unbounded_;
};

}  // namespace ab
