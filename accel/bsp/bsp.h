// BSP tree with arbitrary split planes (Ize, Wald and Parker 2008, "Ray tracing with the BSP tree"; the
// build: builder.h), walked front to back like the k-d trees (plane_tree_walk.h) with the one plane step at
// t_split = (d - n.o) / (n.dir) (PlaneRay::cross of an arbitrary plane, split_plane.h).
#pragma once

#include <memory>
#include <vector>

#include "accel/bsp/builder.h"
#include "accel/bsp/candidates.h"
#include "accel/bsp/config.h"
#include "accel/bsp/node.h"
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

namespace ab {

/// The BSP tree as the one statistics walk sees it (tree_stats.h): a node is its index; a child that its
/// parent flags empty is an empty leaf without a node of its own. The cells are convex polyhedra, not
/// boxes: the visitor gives no areas, so the walk reports no tree SAH cost (0, as the BSP tree always has).
struct BspStatsVisitor {
  /// A node of the walk.
  struct Node {
    uint32_t index;      ///< stored node (unused when flagged empty)
    bool flagged_empty;  ///< an empty leaf its parent flags (no stored node)
  };
  const std::vector<BspNode>& nodes;  ///< the stored nodes

  /// The root (node 0).
  Node root() const { return {0, false}; }
  /// No box (area 0): the BSP's cost is over its cells' true areas, which the tree does not keep.
  AABB box(const Node&) const { return AABB{}; }
  /// True for leaves, flagged empty children included.
  bool is_leaf(const Node& n) const { return n.flagged_empty || nodes[n.index].is_leaf(); }
  /// Primitives of a leaf.
  uint32_t count(const Node& n) const { return n.flagged_empty ? 0 : nodes[n.index].count(); }
  /// The above child, then the below child.
  template <class F>
  void children(const Node& n, F&& f) const {
    const BspNode& b = nodes[n.index];
    f(Node{b.above_empty() ? 0 : b.above(), b.above_empty()});
    f(Node{n.index + 1, b.below_empty()});
  }
};

/// BSP tree (registry name bsp).
template <class P>
class BspTree final : public SpatialTreeQueries<BspTree<P>> {
  friend class SpatialTreeQueries<BspTree<P>>;

 public:
  /// The primitive set.
  using Prims = P;
  /// The BSP tree's configuration (config.h).
  using Config = BspConfig;

  /// Over prims with config; the build is separate.
  BspTree(std::shared_ptr<const P> prims, const Config& config) : prims_(std::move(prims)), config_(config) {}

  /// Bounds of the primitives.
  AABB bounds() const override { return prims_->bounds(); }

 protected:
  void do_build() override {
    std::vector<uint32_t> ids = partition_finite(*prims_, unbounded_, box_);
    const int depth_limit = config_.max_depth > 0 ? config_.max_depth : auto_depth_limit(ids.size());
    origin_ = frame_origin(box_);
    const AABB local{box_.lo - origin_, box_.hi - origin_};
    margin_ = ids.empty() ? 0.0f : insertion_margin(local);
    BspBuffer out;
    if (!ids.empty()) {
      BspBuilder<P> builder(*prims_, config_, depth_limit, margin_, origin_);
      builder.build(std::move(ids), local, out);
      this->stats_.extra["budget_exhausted"] = builder.budget_exhausted();
    }
    drop_empty_leaves(out.nodes);
    nodes_ = std::move(out.nodes);
    planes_ = std::move(out.payload);
    leaves_.assign(*prims_, std::move(out.refs), config_.leaf_copies);
    this->stats_.extra["depth_limit"] = depth_limit;
  }

  void gather_stats(BuildStats& stats) const override {
    stats.primitives = prims_->size();
    stats.bytes = nodes_.size() * sizeof(BspNode) + planes_.size() * sizeof(BspPlane) + leaves_.bytes() +
                  unbounded_.size() * sizeof(uint32_t);
    stats.extra["unbounded_primitives"] = unbounded_.size();
    stats.extra["never_hit_primitives"] = count_never_hit(*prims_);
    stats.extra["leaf_copies"] = leaves_.copied();
    size_t axis_planes = 0;
    for (const BspPlane& p : planes_) axis_planes += !is_oblique(p);
    stats.extra["axis_aligned_planes"] = axis_planes;
    stats.extra["oblique_planes"] = planes_.size() - axis_planes;
    stats.extra["stored_nodes"] = nodes_.size();  // nodes: also the empty leaves, which are flags, not nodes
    if (!nodes_.empty()) walk_tree_stats(BspStatsVisitor{nodes_}, stats);
  }

 private:
  /// The walk over the leaves met by the ray (plane_tree_walk.h), each plane step with the band of an
  /// arbitrary plane (PlaneRay::cross).
  template <bool kCount, class Leaf, class BestT>
  [[gnu::always_inline]] bool traverse(const Ray& ray, RayCounters& c, Leaf&& leaf, BestT&& best_t) const {
    float t0 = ray.tmin, t1 = ray.tmax;
    if (nodes_.empty() || !slab_test(box_, RayBoxData(ray), t0, t1)) return false;
    Ray local = ray;
    local.org -= origin_;  // the planes' frame (the kernel gets the ray as it is)
    const PlaneRay r(local, margin_);
    const BspPlane* planes = planes_.data();
    return walk_plane_tree<kCount>(
        nodes_.data(), t0, t1, c,
        [&](const BspNode& n) {
          const BspPlane& p = planes[n.plane()];
          return r.cross(p.n, p.d);
        },
        leaf, best_t);
  }

  std::shared_ptr<const P> prims_;
  Config config_;
  /// The origin of the tree's frame (issue 11, geometry far from the origin). Far from the world's origin
  /// every band of the build and the walk scales with the coordinates: an oblique plane's offset and a
  /// clipped point carry their rounding (an ulp of 1e6 is 1/16), so the insertion margin (2^-18 of them,
  /// 3.8 at 1e6), the cell clipper's bands and the walk's band (2^-20 of |d| + |n|.|o|) all grew beyond
  /// small triangles there, and most cells held most of the mesh. In a frame at the root box's centre the
  /// planes, cells and parts have the mesh's own magnitude; the triangles' translation rounds by at most
  /// half an ulp of that magnitude (nothing at all far away: both sides of v - c are close), which the
  /// margin (2^-18 of it) covers; the ray origin's translation rounds by half an ulp of |o - c|, which the
  /// walk's band (2^-20 of |n|.|o - c|) covers. A tree not far_from_origin (conservative_insertion.h) keeps
  /// the world's frame, so those trees are the same bit for bit.
  static vec3 frame_origin(const AABB& root) { return far_from_origin(root) ? root.center() : vec3(0.0f); }

  float margin_ = 0.0f;  ///< insertion margin, also the positional band of every plane crossing (PlaneRay)
  vec3 origin_{0.0f};    ///< the origin of the planes' frame (frame_origin), in world coordinates
  AABB box_;
  std::vector<BspNode> nodes_;
  std::vector<BspPlane> planes_;
  LeafRefs<P> leaves_;
  std::vector<uint32_t> unbounded_;
};

}  // namespace ab
