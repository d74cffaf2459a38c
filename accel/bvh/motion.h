// bvh-motion: a motion BVH (Woop et al. 2017, "STBVH: a spatial-temporal BVH for efficient multi-segment
// motion blur"; Embree's linear-bounds BVHs): per node a linear bound over a time range, interpolated at the
// ray's time and tested with the one robust slab test (Ize 2013); temporal splits for multi-segment motion
// (motion_build.h). Over static primitives every bound is constant and it is a binary SAH BVH.
#pragma once

#include <memory>
#include <vector>

#include "accel/bvh/config.h"
#include "accel/bvh/motion_build.h"
#include "accel/bvh/motion_node.h"
#include "accel/bvh/walk2.h"
#include "accel/common/leaf_refs.h"
#include "accel/common/tree_stats.h"
#include "accel/core/accelerator.h"
#include "accel/core/box_test.h"
#include "accel/core/params.h"

namespace ab {

/// bvh-motion's configuration: the SAH tree's (max_leaf_size, costs, max_depth) and the bins per axis.
struct BvhMotionConfig : BvhSahTreeConfig {
  int bins = 16;  ///< bins per axis of the object split

  /// Reads every field.
  static BvhMotionConfig read(Params& params) {
    BvhMotionConfig c;
    c.read_sah_tree(params);
    params.read("bins", c.bins, 2, 256);
    return c;
  }
};

/// What the statistics walk sees of the motion tree (boxes: each node's hull over its range).
struct MotionBvhTreeVisitor {
  const std::vector<MotionBvhNode>& nodes;
  using Node = uint32_t;
  Node root() const { return 0; }
  AABB box(Node n) const { return nodes[n].hull(); }
  bool is_leaf(Node n) const { return nodes[n].is_leaf(); }
  uint32_t count(Node n) const { return nodes[n].count; }
  template <class F>
  void children(Node n, F&& f) const {
    f(nodes[n].offset);
    f(nodes[n].offset + 1);
  }
};

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

  /// Closest hit at the ray's time: the one binary walk (walk2.h) with the pair test at the ray's time; a
  /// child is skipped only when its entry is strictly beyond min(tmax, best.t).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if (nodes_.empty()) return;
    const auto limit = [&] { return std::min(ray.tmax, best.t); };
    const auto leaf = [&](uint32_t first, uint32_t count) {
      refs_.template intersect<kCount>(*prims_, first, count, ray, best, inst, c);
      return false;
    };
    walk_bvh2<kCount, true>(nodes_.data(), ray, limit, leaf, c);
  }
  /// Any hit at the ray's time.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    if (nodes_.empty()) return false;
    const auto limit = [&] { return ray.tmax; };
    const auto leaf = [&](uint32_t first, uint32_t count) {
      return refs_.template occluded<kCount>(*prims_, first, count, ray, c);
    };
    return walk_bvh2<kCount, false>(nodes_.data(), ray, limit, leaf, c);
  }

 protected:
  void do_build() override {
    MotionBuildSettings s;
    s.costs = config_.costs;
    s.bins = config_.bins;
    s.max_leaf_size = config_.max_leaf_size;
    s.max_depth = config_.max_depth;
    MotionBvhBuild result = MotionBvhBuilder<P>(*prims_, s).build();
    nodes_ = std::move(result.nodes);
    refs_.assign(*prims_, std::move(result.refs), LeafCopies::kAuto);  // triangles copied into leaf order
  }
  void gather_stats(BuildStats& stats) const override {
    stats.primitives = prims_->size();
    if (!nodes_.empty()) walk_tree_stats(MotionBvhTreeVisitor{nodes_}, stats);
    size_t temporal = 0;
    for (size_t n = 0; n < nodes_.size(); ++n)
      temporal += !nodes_[n].is_leaf() && nodes_[nodes_[n].offset].t1 < nodes_[n].t1;
    stats.extra["temporal_splits"] = temporal;
    stats.bytes = nodes_.size() * sizeof(MotionBvhNode) + refs_.bytes();
  }

 private:
  std::shared_ptr<const P> prims_;
  Config config_;
  std::vector<MotionBvhNode> nodes_;
  LeafRefs<P> refs_;
};

}  // namespace ab
