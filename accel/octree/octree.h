// Adaptive octree over a primitive set: a cube around the scene, subdivided into eight equal children
// while a node holds more than leaf_size primitives and is above the depth limit. Primitives are inserted
// by exact triangle/box overlap against the child boxes grown by the insertion margin (clip.h), so a
// primitive touching a cell or within rounding of its boundary is in every such cell.
//
// Traversal follows the parametric idea of Revelles, Urena and Lastra 2000 ("An efficient parametric
// algorithm for octree traversal"): the children are visited front to back by the ray parameters at which
// it crosses the node's three mid-planes. Here the crossing of each mid-plane is one robust plane step
// (split_plane.h), taken in turn for x, y and z, which orders the up to four children a ray meets, handles
// zero direction components and rays lying in a mid-plane, and widens every cell's interval. A cell is
// pruned only when its entry lies strictly beyond the best hit so far.
#pragma once

#include "accel/core/box_test.h"
#include "accel/core/accelerator.h"
#include "accel/core/clip.h"
#include "accel/common/spatial_tree.h"
#include "accel/core/params.h"
#include "accel/common/split_plane.h"

#include <tbb/parallel_for.h>

#include <array>
#include <memory>
#include <string>
#include <vector>

namespace ab {

/// One octree node (8 bytes): an interior node (index of the first of its eight consecutive children) or
/// a leaf (offset and count of its primitive indices).
class OctNode {
 public:
  /// A leaf of `count` primitive indices starting at `first`.
  static OctNode leaf(uint32_t first, uint32_t count) { return OctNode(first, count | kLeafBit); }
  /// An interior node whose children are nodes first_child .. first_child + 7 (child c has bit a of c set
  /// when it is the upper half along axis a).
  static OctNode interior(uint32_t first_child) { return OctNode(first_child, 0); }

  /// True for a leaf.
  bool is_leaf() const { return (bits_ & kLeafBit) != 0; }
  /// First child (interior) or first primitive index (leaf).
  uint32_t first() const { return word_; }
  /// Number of primitives (leaves).
  uint32_t count() const { return bits_ & ~kLeafBit; }
  /// Moves the node by node_base nodes and prim_base primitive indices (splicing buffers).
  void rebase(uint32_t node_base, uint32_t prim_base) { word_ += is_leaf() ? prim_base : node_base; }

 private:
  static constexpr uint32_t kLeafBit = 0x80000000u;
  OctNode(uint32_t word, uint32_t bits) : word_(word), bits_(bits) {}
  uint32_t word_;
  uint32_t bits_;
};
static_assert(sizeof(OctNode) == 8);

/// Box of child c of box b (bit a of c: upper half along axis a). Build and traversal use this same
/// arithmetic, so their planes are the same floats.
inline AABB octant_box(const AABB& b, int c) {
  AABB out = b;
  for (int a = 0; a < 3; ++a) {
    const float mid = 0.5f * (b.lo[a] + b.hi[a]);
    if ((c >> a) & 1) out.lo[a] = mid;
    else out.hi[a] = mid;
  }
  return out;
}

/// Adaptive octree (registry name octree).
template <class P>
class Octree final : public SpatialTreeQueries<Octree<P>> {
  friend class SpatialTreeQueries<Octree<P>>;

 public:
  /// Reads leaf_size and max_depth from params.
  Octree(std::shared_ptr<const P> prims, Params& params) : prims_(std::move(prims)) {
    leaf_size_ = size_t(params.get_int("leaf_size", 8, 1, 1 << 20));
    max_depth_ = int(params.get_int("max_depth", 10, 0, 20));
    leaf_copies_ = read_leaf_copies(params);
    config_ = params.effective();
  }

  std::string name() const override { return "octree"; }
  nlohmann::json config() const override { return config_; }
  AABB bounds() const override { return prims_->bounds(); }

 protected:
  void do_build() override {
    AABB box;
    std::vector<uint32_t> ids = partition_finite(*prims_, unbounded_, box);
    box_ = cube_around(box);
    KdLikeBuffer out;
    out.nodes.push_back(OctNode::leaf(0, 0));
    if (!ids.empty()) build_node(std::move(ids), box_, 0, 0, out);
    nodes_ = std::move(out.nodes);
    leaves_.assign(*prims_, std::move(out.prims), leaf_copies_);
    fill_stats();
  }

 private:
  /// Nodes (children of a node consecutive) and primitive indices under construction.
  struct KdLikeBuffer {
    std::vector<OctNode> nodes;
    std::vector<uint32_t> prims;
  };
  /// A cell on the traversal stack: node, the mid-plane level reached inside it (0..3), the octant bits
  /// chosen so far, the ray interval and the box of the part still to split.
  struct Cell {
    uint32_t node;
    int level;
    int octant;
    float t0, t1;
    AABB box;
  };
  static constexpr int kStackSize = 3 * 21 + 4;

  static AABB cube_around(const AABB& b) {
    if (b.empty()) return b;
    const vec3 c = b.center();
    const vec3 e = b.extent();
    float half = 0.5f * std::max({e.x, e.y, e.z});
    if (!(half > 0.0f)) half = std::max(1.0f, std::max({std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)})) * 0x1p-10f;
    AABB out{c - vec3(half), c + vec3(half)};
    out.extend(b);  // rounding never leaves a vertex outside
    return out;
  }

  /// Shared traversal; leaf(first, count) returns true to stop (any hit); best_t() is the pruning distance.
  template <bool kCount, class Leaf, class BestT>
  bool traverse(const Ray& ray, RayCounters& c, Leaf&& leaf, BestT&& best_t) const {
    float t0 = ray.tmin, t1 = ray.tmax;
    if (nodes_.empty() || box_.empty() || !slab_test(box_, RayBoxData(ray), t0, t1)) return false;
    const RayAxes axes(ray);
    Cell stack[kStackSize];
    int sp = 0;
    Cell cur{0, 0, 0, t0, t1, box_};
    if constexpr (kCount) ++c.nodes;
    while (true) {
      const OctNode& n = nodes_[cur.node];
      if (n.is_leaf()) {
        if constexpr (kCount) ++c.leaves;
        if (n.count() && leaf(n.first(), n.count())) return true;
      } else if (cur.level == 3) {
        cur = {n.first() + uint32_t(cur.octant), 0, 0, cur.t0, cur.t1, cur.box};
        if constexpr (kCount) ++c.nodes;
        continue;
      } else if (split_cell(cur, axes, stack, sp)) {
        continue;
      }
      if (!pop(stack, sp, best_t(), cur)) return false;
    }
  }

  /// Splits the current cell at its mid-plane of axis cur.level; continues into the first half met.
  [[gnu::always_inline]] static bool split_cell(Cell& cur, const RayAxes& r, Cell* stack, int& sp) {
    const int a = cur.level;
    const float mid = 0.5f * (cur.box.lo[a] + cur.box.hi[a]);
    const PlaneVisit v = split_at_axis_plane(r.org[a], r.dir[a], r.inv[a], mid, cur.t0, cur.t1);
    Cell below = cur, above = cur;
    below.level = above.level = a + 1;
    below.box.hi[a] = mid;
    above.box.lo[a] = mid;
    above.octant |= 1 << a;
    Cell& first = v.first_below ? below : above;
    Cell& second = v.first_below ? above : below;
    first.t1 = v.first_t1;
    second.t0 = v.second_t0;
    if (v.visit_first && v.visit_second) stack[sp++] = second;
    if (v.visit_first) cur = first;
    else if (v.visit_second) cur = second;
    else return false;
    return true;
  }

  [[gnu::always_inline]] static bool pop(const Cell* stack, int& sp, float best_t, Cell& cur) {
    while (sp > 0) {
      const Cell& it = stack[--sp];
      if (it.t0 > best_t) continue;
      cur = it;
      return true;
    }
    return false;
  }

  /// Builds node `self` (already allocated) over ids inside box.
  void build_node(std::vector<uint32_t>&& ids, const AABB& box, int depth, uint32_t self, KdLikeBuffer& out) const {
    std::array<std::vector<uint32_t>, 8> kids;
    if (ids.size() > leaf_size_ && depth < max_depth_) distribute(ids, box, kids);
    bool progress = false;
    for (const auto& k : kids) progress |= !k.empty() && k.size() < ids.size();
    if (!progress) {
      out.nodes[self] = OctNode::leaf(uint32_t(out.prims.size()), uint32_t(ids.size()));
      out.prims.insert(out.prims.end(), ids.begin(), ids.end());
      return;
    }
    const size_t n = ids.size();
    std::vector<uint32_t>().swap(ids);
    const uint32_t first = uint32_t(out.nodes.size());
    out.nodes[self] = OctNode::interior(first);
    out.nodes.resize(first + 8, OctNode::leaf(0, 0));
    if (n < kParallelMin) {
      for (int k = 0; k < 8; ++k) build_node(std::move(kids[k]), octant_box(box, k), depth + 1, first + k, out);
      return;
    }
    std::array<KdLikeBuffer, 8> subs;
    tbb::parallel_for(0, 8, [&](int k) {
      subs[k].nodes.push_back(OctNode::leaf(0, 0));
      build_node(std::move(kids[k]), octant_box(box, k), depth + 1, 0, subs[k]);
    });
    for (int k = 0; k < 8; ++k) splice(subs[k], first + k, out);
  }

  /// Appends a child subtree built with its root at index 0 into out, its root going to slot `slot`.
  static void splice(const KdLikeBuffer& sub, uint32_t slot, KdLikeBuffer& out) {
    const uint32_t node_base = uint32_t(out.nodes.size()) - 1;
    const uint32_t prim_base = uint32_t(out.prims.size());
    for (size_t i = 0; i < sub.nodes.size(); ++i) {
      OctNode n = sub.nodes[i];
      n.rebase(node_base, prim_base);
      if (i == 0) out.nodes[slot] = n;
      else out.nodes.push_back(n);
    }
    out.prims.insert(out.prims.end(), sub.prims.begin(), sub.prims.end());
  }

  /// Exact overlap of every primitive with the eight (grown) child boxes.
  void distribute(const std::vector<uint32_t>& ids, const AABB& box, std::array<std::vector<uint32_t>, 8>& kids) const {
    for (int k = 0; k < 8; ++k) {
      const AABB grown = inflate_for_insertion(octant_box(box, k));
      for (uint32_t i : ids)
        if (prims_->overlaps(i, grown)) kids[k].push_back(i);
    }
  }

  void fill_stats() {
    BuildStats& st = this->stats_;
    st = BuildStats{};
    st.primitives = prims_->size();
    st.nodes = nodes_.size();
    st.bytes = nodes_.size() * sizeof(OctNode) + leaves_.bytes() + unbounded_.size() * 4;
    st.extra["leaf_copies"] = leaves_.copied();
    st.extra["unbounded_primitives"] = unbounded_.size();
    struct Item {
      uint32_t node, depth;
      AABB box;
    };
    std::vector<Item> todo{{0, 0, box_}};
    double sah = 0.0;
    const double root_area = box_.area();
    while (!todo.empty() && !nodes_.empty()) {
      const Item it = todo.back();
      todo.pop_back();
      const OctNode& n = nodes_[it.node];
      const double p = root_area > 0.0 ? it.box.area() / root_area : 1.0;
      if (n.is_leaf()) {
        st.add_leaf(n.count(), it.depth);
        sah += p * n.count();
        continue;
      }
      sah += p;
      for (int k = 0; k < 8; ++k) todo.push_back({n.first() + k, it.depth + 1, octant_box(it.box, k)});
    }
    st.sah_cost = sah;
  }

  static constexpr size_t kParallelMin = 20000;
  std::shared_ptr<const P> prims_;
  size_t leaf_size_ = 8;
  int max_depth_ = 10;
  nlohmann::json config_;
  AABB box_;
  std::vector<OctNode> nodes_;
  LeafCopies leaf_copies_ = LeafCopies::kAuto;  ///< copy triangles into leaf order (LeafRefs)
  LeafRefs<P> leaves_;
  std::vector<uint32_t> unbounded_;
};

}  // namespace ab
