// bvh-motion: a motion BVH (Woop et al. 2017, "STBVH: a spatial-temporal BVH for efficient multi-segment
// motion blur"; Embree's linear-bounds BVHs): per node a linear bound over a time range, interpolated at the
// ray's time and tested with the one robust slab test (Ize 2013); temporal splits for multi-segment motion
// (motion_build.h). The binary tree is collapsed into 8-wide motion nodes whose eight boxes are interpolated
// at once (motion_node8.h; Embree's BVH8 motion nodes). A primitive set of which nothing moves (a static
// mesh's bottom, a top over static instances) gets the static BVH (bvh-sah's 8-wide tree), as Embree builds
// geometry with one time step into its static BVHs and only motion geometry into its motion BVHs.
#pragma once

#include <memory>
#include <vector>

#include "accel/bvh/bvh.h"
#include "accel/bvh/config.h"
#include "accel/bvh/motion_build.h"
#include "accel/bvh/motion_node.h"
#include "accel/bvh/motion_node8.h"
#include "accel/bvh/tree_visitors.h"
#include "accel/bvh/walk2.h"
#include "accel/bvh/walk8.h"
#include "accel/common/leaf_refs.h"
#include "accel/common/tree_stats.h"
#include "accel/core/accelerator.h"
#include "accel/core/box_test.h"
#include "accel/core/params.h"

namespace ab {

/// bvh-motion's configuration: the SAH tree's (max_leaf_size, costs, max_depth), the bins per axis of the
/// motion tree and the node width (8: the collapsed tree, 2: the binary one).
struct BvhMotionConfig : BvhSahTreeConfig {
  int bins = 16;  ///< bins per axis of the object split
  int width = 8;  ///< node width, 2 or 8

  /// Reads every field.
  static BvhMotionConfig read(Params& params) {
    BvhMotionConfig c;
    c.read_sah_tree(params);
    params.read("bins", c.bins, 2, 256);
    read_bvh_width(params, c.width);
    return c;
  }
  /// The static BVH's configuration for primitives that do not move: bvh-sah's, with this tree's fields.
  BvhSahConfig static_config() const {
    BvhSahConfig c;
    static_cast<BvhSahTreeConfig&>(c) = *this;
    return c;
  }
};

/// What the statistics walk sees of the binary motion tree (boxes: each node's hull over its range).
using MotionBvhTreeVisitor = BinaryTreeVisitor<std::vector<MotionBvhNode>, &MotionBvhNode::hull>;
/// What it sees of the 8-wide motion tree (a lane's hull over its range).
using MotionBvh8TreeVisitor = WideTreeVisitor<MotionBvh8NodeArray>;

/// True when some primitive of p moves (has more than one time step).
template <class P>
bool any_primitive_moves(const P& p) {
  for (size_t i = 0; i < p.size(); ++i)
    if (motion_steps(p, i) > 1) return true;
  return false;
}

/// The motion BVH over primitive set P.
template <class P>
class BvhMotion final : public AcceleratorBase<BvhMotion<P>> {
 public:
  using Prims = P;
  using Config = BvhMotionConfig;

  /// Over prims (built by build()).
  BvhMotion(std::shared_ptr<const P> prims, const Config& config)
      : prims_(std::move(prims)), config_(config) {}

  AABB bounds() const override { return prims_->bounds(); }

  /// Closest hit at the ray's time: the static tree's walk when nothing moves, else the one 8-wide walk
  /// (walk8.h) over the motion nodes (or the one binary walk, walk2.h, for width 2) with the boxes at the
  /// ray's time; a child is skipped only when its entry is strictly beyond min(tmax, best.t).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if (static_) return static_->template intersect_ray<kCount>(ray, best, inst, c);
    const auto limit = [&] { return std::min(ray.tmax, best.t); };
    const auto leaf = [&](uint32_t first, uint32_t count) {
      refs_.template intersect<kCount>(*prims_, first, count, ray, best, inst, c);
      return false;
    };
    if (!wide_.empty())
      walk_bvh8<kCount, true>(wide_.data(), ray, limit, leaf, nullptr, 0, c);
    else if (!nodes_.empty())
      walk_bvh2<kCount, true>(nodes_.data(), ray, limit, leaf, c);
  }
  /// Any hit at the ray's time.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    if (static_) return static_->template occluded_ray<kCount>(ray, c);
    const auto limit = [&] { return ray.tmax; };
    const auto leaf = [&](uint32_t first, uint32_t count) {
      return refs_.template occluded<kCount>(*prims_, first, count, ray, c);
    };
    if (!wide_.empty()) return walk_bvh8<kCount, false>(wide_.data(), ray, limit, leaf, nullptr, 0, c);
    return !nodes_.empty() && walk_bvh2<kCount, false>(nodes_.data(), ray, limit, leaf, c);
  }
  /// The 8-wide motion nodes (empty for width 2 or the static tree; for tests).
  const MotionBvh8NodeArray& wide_nodes() const { return wide_; }
  /// True when the static tree serves the primitives (none of them moves).
  bool uses_static_tree() const { return static_ != nullptr; }

 protected:
  void do_build() override {
    static_.reset();
    nodes_.clear();
    wide_.clear();
    if (!any_primitive_moves(*prims_)) {
      static_ = std::make_unique<BvhSah<P>>(prims_, config_.static_config());
      static_->build();
      return;
    }
    MotionBuildSettings s;
    s.costs = config_.costs;
    s.bins = config_.bins;
    s.max_leaf_size = config_.max_leaf_size;
    s.max_depth = config_.max_depth;
    s.parallel_threshold = config_.parallel_threshold;
    MotionBvhBuild result = MotionBvhBuilder<P>(*prims_, s).build();
    nodes_ = std::move(result.nodes);
    refs_.assign(*prims_, std::move(result.refs), LeafCopies::kAuto);  // triangles copied into leaf order
    if (config_.width == 8 && !nodes_.empty()) {
      wide_ = collapse_motion_bvh(nodes_);
      temporal_splits_ = count_temporal_splits();
      std::vector<MotionBvhNode>().swap(nodes_);
    }
  }
  void gather_stats(BuildStats& stats) const override {
    if (static_) {
      const double seconds = stats.build_seconds;  // this build's own time and memory
      const uint64_t peak = stats.peak_bytes;
      stats = static_->stats();
      stats.build_seconds = seconds, stats.peak_bytes = peak;
      stats.extra["static_tree"] = true;
      return;
    }
    stats.primitives = prims_->size();
    stats.extra["static_tree"] = false;
    stats.extra["width"] = config_.width;
    if (!wide_.empty()) {
      walk_tree_stats(MotionBvh8TreeVisitor{wide_}, stats);
      stats.extra["temporal_splits"] = temporal_splits_;
      stats.bytes = wide_.size() * sizeof(MotionBvh8Node) + refs_.bytes();
      return;
    }
    if (!nodes_.empty()) walk_tree_stats(MotionBvhTreeVisitor{nodes_}, stats);
    stats.extra["temporal_splits"] = count_temporal_splits();
    stats.bytes = nodes_.size() * sizeof(MotionBvhNode) + refs_.bytes();
  }

 private:
  /// Interior nodes of the binary tree split in time (their first child ends before them).
  size_t count_temporal_splits() const {
    size_t temporal = 0;
    for (size_t n = 0; n < nodes_.size(); ++n)
      temporal += !nodes_[n].is_leaf() && nodes_[nodes_[n].offset].t1 < nodes_[n].t1;
    return temporal;
  }

  std::shared_ptr<const P> prims_;
  Config config_;
  std::unique_ptr<BvhSah<P>> static_;  ///< the static tree, when no primitive moves
  std::vector<MotionBvhNode> nodes_;   ///< the binary motion tree (width 2)
  MotionBvh8NodeArray wide_;           ///< the 8-wide motion tree (width 8)
  size_t temporal_splits_ = 0;         ///< the binary tree's temporal splits (width 8)
  LeafRefs<P> refs_;
};

}  // namespace ab
