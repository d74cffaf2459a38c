// k-d trees over a primitive set: `kdtree-median` (median splits, median_builder.h) and `kdtree-sah` (the
// O(N log N) SAH build of Wald and Havran 2006, sah_builder.h). Both share the compact node (node.h) and the
// walk of every binary plane tree (plane_tree_walk.h).
#pragma once

#include <memory>
#include <type_traits>
#include <vector>

#include "accel/common/conservative_insertion.h"
#include "accel/common/depth_limit.h"
#include "accel/common/empty_leaves.h"
#include "accel/common/finite_primitives.h"
#include "accel/common/leaf_refs.h"
#include "accel/common/plane_tree_walk.h"
#include "accel/common/spatial_tree_queries.h"
#include "accel/common/split_plane.h"
#include "accel/common/tree_stats.h"
#include "accel/core/box_test.h"
#include "accel/kdtree/config.h"
#include "accel/kdtree/median_builder.h"
#include "accel/kdtree/node.h"
#include "accel/kdtree/sah_builder.h"

namespace ab {

/// Which builder a k-d tree uses.
enum class KdMethod { kMedian, kSah };

/// The k-d tree as the one statistics walk sees it (tree_stats.h): a node is its index and box; a child
/// that its parent flags empty is an empty leaf without a node of its own.
struct KdStatsVisitor {
  /// A node of the walk.
  struct Node {
    uint32_t index;      ///< stored node (unused when flagged empty)
    AABB box;            ///< its box
    bool flagged_empty;  ///< an empty leaf its parent flags (no stored node)
  };
  const std::vector<KdNode>& nodes;  ///< the stored nodes
  AABB root_box;                     ///< the box of the finite primitives

  /// The root (node 0, the box of the finite primitives).
  Node root() const { return {0, root_box, false}; }
  /// The node's box.
  AABB box(const Node& n) const { return n.box; }
  /// True for leaves, flagged empty children included.
  bool is_leaf(const Node& n) const { return n.flagged_empty || nodes[n.index].is_leaf(); }
  /// Primitives of a leaf.
  uint32_t count(const Node& n) const { return n.flagged_empty ? 0 : nodes[n.index].count(); }
  /// The above child, then the below child, each with its half of the box.
  template <class F>
  void children(const Node& n, F&& f) const {
    const KdNode& k = nodes[n.index];
    AABB below = n.box, above = n.box;
    below.hi[k.axis()] = k.split();
    above.lo[k.axis()] = k.split();
    f(Node{k.above_empty() ? 0 : k.above(), above, k.above_empty()});
    f(Node{n.index + 1, below, k.below_empty()});
  }
};

/// A k-d tree. Traversal: the binary plane-tree walk (Havran 2000, TA_B rec), one robust plane step
/// (split_plane.h) per interior node, leaves pruned only when their entry lies strictly beyond the best hit
/// so far.
template <class P, KdMethod M>
class KdTree final : public SpatialTreeQueries<KdTree<P, M>> {
  friend class SpatialTreeQueries<KdTree<P, M>>;

 public:
  /// The primitive set.
  using Prims = P;
  /// KdMedianConfig or KdSahConfig (config.h).
  using Config = std::conditional_t<M == KdMethod::kSah, KdSahConfig, KdMedianConfig>;

  /// Over prims with config; the build is separate.
  KdTree(std::shared_ptr<const P> prims, const Config& config) : prims_(std::move(prims)), config_(config) {}

  /// Bounds of the primitives.
  AABB bounds() const override { return prims_->bounds(); }

 protected:
  void do_build() override {
    // NaN or infinite coordinates: tested for every ray.
    std::vector<uint32_t> ids = partition_finite(*prims_, unbounded_, box_);
    const int depth_limit = config_.max_depth > 0 ? config_.max_depth : auto_depth_limit(ids.size());
    KdBuffer out;
    if (!ids.empty()) {
      if constexpr (M == KdMethod::kSah) {
        KdSahBuilder<P> builder(*prims_, config_, depth_limit);
        builder.build(ids, box_, out);
        this->stats_.extra["budget_exhausted"] = builder.budget_exhausted();
      } else {
        KdMedianBuilder<P> builder(*prims_, config_, depth_limit);
        builder.build(ids, box_, out);
        this->stats_.extra["budget_exhausted"] = builder.budget_exhausted();
      }
    }
    drop_empty_leaves(out.nodes);
    margin_ = ids.empty() ? 0.0f : InsertionMargin(box_).of(box_);
    root_box_ = {box_.lo - vec3(margin_), box_.hi + vec3(margin_)};
    nodes_ = std::move(out.nodes);
    leaves_.assign(*prims_, std::move(out.refs), config_.leaf_copies);
    this->stats_.extra["depth_limit"] = depth_limit;
  }

  void gather_stats(BuildStats& stats) const override {
    stats.primitives = prims_->size();
    stats.bytes = nodes_.size() * sizeof(KdNode) + leaves_.bytes() + unbounded_.size() * sizeof(uint32_t);
    stats.extra["unbounded_primitives"] = unbounded_.size();
    stats.extra["never_hit_primitives"] = count_never_hit(*prims_);
    stats.extra["leaf_copies"] = leaves_.copied();
    if (nodes_.empty()) return;
    walk_tree_stats(KdStatsVisitor{nodes_, box_}, stats);
    stats.extra["stored_nodes"] = nodes_.size();  // nodes: also the empty leaves, which are flags, not nodes
  }

 private:
  /// The walk over the leaves met by the ray (plane_tree_walk.h); leaf(first, count) returns true to stop
  /// (any hit); an entry is popped only when its t0 is not beyond best_t().
  template <bool kCount, class Leaf, class BestT>
  [[gnu::always_inline]] bool traverse(const Ray& ray, RayCounters& c, Leaf&& leaf, BestT&& best_t) const {
    float t0 = ray.tmin, t1 = ray.tmax;
    if (nodes_.empty() || !slab_test(root_box_, RayBoxData(ray), t0, t1)) return false;
    const PlaneRay r(ray, margin_);
    return walk_plane_tree<kCount>(
        nodes_.data(), t0, t1, c, [&](const KdNode& n) { return r.cross(n.axis(), n.split()); }, leaf,
        best_t);
  }

  std::shared_ptr<const P> prims_;
  Config config_;
  AABB box_;
  AABB root_box_;        ///< box_ grown by margin_ (the traversal's first clip)
  float margin_ = 0.0f;  ///< positional band of every plane crossing (PlaneRay)
  std::vector<KdNode> nodes_;
  LeafRefs<P> leaves_;
  std::vector<uint32_t> unbounded_;
};

/// The median-split k-d tree (registry name kdtree-median).
template <class P>
using KdTreeMedian = KdTree<P, KdMethod::kMedian>;
/// The SAH k-d tree (registry name kdtree-sah).
template <class P>
using KdTreeSah = KdTree<P, KdMethod::kSah>;

}  // namespace ab
