// Adaptive octree over a primitive set (the build: builder.h).
//
// Traversal follows the parametric idea of Revelles, Urena and Lastra 2000 ("An efficient parametric
// algorithm for octree traversal"): the children are visited front to back by the ray parameters at which
// it crosses the node's three mid-planes. Here the crossing of each mid-plane is the one robust plane step
// (split_plane.h), taken in turn for x, y and z, which orders the up to four children a ray meets, handles
// zero direction components and rays lying in a mid-plane, and widens every cell's interval (relatively and
// by the insertion margin of the root cube, which covers every cell's inflation). A cell is pruned only when
// its entry lies strictly beyond the best hit so far.
#pragma once

#include <algorithm>
#include <memory>
#include <vector>

#include "accel/common/conservative_insertion.h"
#include "accel/common/depth_limit.h"
#include "accel/common/finite_primitives.h"
#include "accel/common/leaf_refs.h"
#include "accel/common/mailbox.h"
#include "accel/common/spatial_tree_queries.h"
#include "accel/common/split_plane.h"
#include "accel/common/traversal_stack.h"
#include "accel/common/tree_stats.h"
#include "accel/core/box_test.h"
#include "accel/octree/builder.h"
#include "accel/octree/config.h"
#include "accel/octree/node.h"

namespace ab {

/// The octree as the one statistics walk sees it (tree_stats.h): a node is its index and box.
struct OctreeStatsVisitor {
  /// A node of the walk.
  struct Node {
    uint32_t index;  ///< stored node
    AABB box;        ///< its box
  };
  const std::vector<OctNode>& nodes;  ///< the stored nodes
  AABB root_box;                      ///< the root cube

  /// The root (node 0, the cube).
  Node root() const { return {0, root_box}; }
  /// The node's box.
  AABB box(const Node& n) const { return n.box; }
  /// True for leaves.
  bool is_leaf(const Node& n) const { return nodes[n.index].is_leaf(); }
  /// Primitives of a leaf.
  uint32_t count(const Node& n) const { return nodes[n.index].count(); }
  /// The eight children in octant order.
  template <class F>
  void children(const Node& n, F&& f) const {
    for (int k = 0; k < 8; ++k) f(Node{nodes[n.index].first() + uint32_t(k), octant_box(n.box, k)});
  }
};

/// Adaptive octree (registry name octree).
template <class P>
class Octree final : public SpatialTreeQueries<Octree<P>> {
  friend class SpatialTreeQueries<Octree<P>>;

 public:
  /// The primitive set.
  using Prims = P;
  /// The octree's configuration (config.h).
  using Config = OctreeConfig;

  /// Over prims with config; the build is separate.
  Octree(std::shared_ptr<const P> prims, const Config& config) : prims_(std::move(prims)), config_(config) {}

  /// Bounds of the primitives.
  AABB bounds() const override { return prims_->bounds(); }

  /// Closest hit, front to back, with a per-ray mailbox (Amanatides and Woo 1987, section 4): a triangle
  /// copied into several cells the ray crosses (on average 4-6 per triangle on the 1M-10M soup and
  /// sphereflake) is tested once. Hides SpatialTreeQueries' closest hit; the any-hit query is its.
  template <bool kCount>
  [[gnu::flatten]] void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if (!unbounded_.empty())
      intersect_id_list<kCount>(*prims_, unbounded_.data(), uint32_t(unbounded_.size()), ray, best, inst, c);
    Mailbox mailbox;
    traverse<kCount>(
        ray, c,
        [&](uint32_t first, uint32_t count) {
          leaves_.template intersect_unseen<kCount>(*prims_, first, count, ray, best, inst, c, mailbox);
          return false;
        },
        [&] { return best.t; });
  }

 protected:
  void do_build() override {
    AABB box;
    std::vector<uint32_t> ids = partition_finite(*prims_, unbounded_, box);
    box_ = cube_around(box);
    margin_ = box_.empty() ? 0.0f : InsertionMargin(box_).of(box_);
    const int depth_limit =
        config_.auto_depth
            ? std::min(Config::kMaxDepth, std::max(config_.max_depth, auto_octree_depth_limit(ids.size())))
            : config_.max_depth;
    OctBuffer out;
    OctreeBuilder<P> builder(*prims_, config_, depth_limit);
    builder.build(std::move(ids), box_, out);
    nodes_ = std::move(out.nodes);
    leaves_.assign(*prims_, std::move(out.refs), config_.leaf_copies);
    this->stats_.extra["depth_limit"] = depth_limit;
    this->stats_.extra["budget_exhausted"] = builder.budget_exhausted();
  }

  void gather_stats(BuildStats& stats) const override {
    stats.primitives = prims_->size();
    stats.bytes = nodes_.size() * sizeof(OctNode) + leaves_.bytes() + unbounded_.size() * sizeof(uint32_t);
    stats.extra["leaf_copies"] = leaves_.copied();
    stats.extra["unbounded_primitives"] = unbounded_.size();
    stats.extra["never_hit_primitives"] = count_never_hit(*prims_);
    walk_tree_stats(OctreeStatsVisitor{nodes_, box_}, stats);
  }

 private:
  /// A cell on the traversal stack: node, the mid-plane level reached inside it (0..3), the octant bits
  /// chosen so far, the ray interval and the box of the part still to split.
  struct Cell {
    uint32_t node;
    int level;
    int octant;
    float t0, t1;
    AABB box;
    /// The entry distance (pruned when beyond the best hit).
    float entry() const { return t0; }
  };
  /// Three cells per level (one per mid-plane) over 20 levels, and the root's.
  static constexpr int kStackSize = 3 * 21 + 4;
  using Stack = TraversalStack<Cell, kStackSize>;

  /// Front-to-back walk; leaf(first, count) returns true to stop (any hit); best_t() is the pruning distance.
  template <bool kCount, class Leaf, class BestT>
  bool traverse(const Ray& ray, RayCounters& c, Leaf&& leaf, BestT&& best_t) const {
    float t0 = ray.tmin, t1 = ray.tmax;
    if (box_.empty() || !slab_test(box_, RayBoxData(ray), t0, t1)) return false;
    const PlaneRay r(ray, margin_);
    Stack stack;
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
      } else if (split_cell(cur, r, stack)) {
        continue;
      }
      if (!stack.pop(best_t(), cur)) return false;
    }
  }

  /// Splits the current cell at its mid-plane of axis cur.level: continues into the first half the ray meets
  /// and stacks the second when the interval reaches it too; false when it reaches neither.
  [[gnu::always_inline]] static bool split_cell(Cell& cur, const PlaneRay& r, Stack& stack) {
    const int a = cur.level;
    const float mid = 0.5f * (cur.box.lo[a] + cur.box.hi[a]);
    const PlaneVisit v = split_interval(r.cross(a, mid), cur.t0, cur.t1);
    if (!v.visit_first && !v.visit_second) return false;
    cur.level = a + 1;
    if (v.visit_first && v.visit_second) {
      Cell second = cur;
      second.t0 = v.second_t0;
      take_half(second, a, mid, v.below_first);
      stack.push(second);
    }
    if (v.visit_first) {
      cur.t1 = v.first_t1;
      take_half(cur, a, mid, !v.below_first);
    } else {
      cur.t0 = v.second_t0;
      take_half(cur, a, mid, v.below_first);
    }
    return true;
  }

  /// Narrows cell c to its half above (or below) the mid-plane `mid` of axis a.
  [[gnu::always_inline]] static void take_half(Cell& c, int a, float mid, bool above) {
    if (above) {
      c.box.lo[a] = mid;
      c.octant |= 1 << a;
    } else {
      c.box.hi[a] = mid;
    }
  }

  std::shared_ptr<const P> prims_;
  Config config_;
  AABB box_;             ///< the root cube
  float margin_ = 0.0f;  ///< positional band of every plane crossing (PlaneRay)
  std::vector<OctNode> nodes_;
  LeafRefs<P> leaves_;
  std::vector<uint32_t> unbounded_;
};

}  // namespace ab
