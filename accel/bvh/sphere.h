// bvh-sphere: a bounding-sphere hierarchy. A binary BVH whose nodes bound their children with spheres
// instead of boxes (the bounding volume of Whitted 1980, "An improved illumination model for shaded
// display", which Weghorst, Hooper and Greenberg 1984, "Improved computational methods for ray tracing",
// compared with boxes and cylinders): the topology is bvh-sah's binary tree
// (binned SAH, Wald 2007; build.h), each node gets the smaller of Ritter's sphere over its points and the
// sphere around its children's (sphere_fit.h), and the one binary walk (walk2.h) tests sibling pairs with
// the conservative ray/sphere test (sphere_entry.h). It is also the worked example of
// docs/adding-a-structure.md.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <memory>
#include <type_traits>
#include <vector>

#include "accel/bvh/build.h"
#include "accel/bvh/sphere_config.h"
#include "accel/bvh/sphere_entry.h"
#include "accel/bvh/sphere_fit.h"
#include "accel/bvh/sphere_node.h"
#include "accel/bvh/tree_visitors.h"
#include "accel/bvh/walk2.h"
#include "accel/common/tree_stats.h"
#include "accel/core/accelerator.h"
#include "accel/core/primitives.h"
#include "accel/core/triangle.h"

namespace ab {

/// The sphere tree as the one statistics walk (accel/common/tree_stats.h) sees it: a node's box its
/// sphere's bounding cube (whose area ratios are the spheres').
using SphereTreeVisitor = BinaryTreeVisitor<SphereNodeArray, &SphereNode::cube>;

/// A bounding-sphere hierarchy over primitive set P (triangles, or instances as a top level: spheres
/// around the instances' world boxes). Triangles are copied into leaf order, as bvh-sah width=2 does.
template <class P>
class BvhSphere final : public AcceleratorBase<BvhSphere<P>> {
 public:
  using Prims = P;                 ///< the primitive set
  using Config = BvhSphereConfig;  ///< the builder's settings

  /// Over prims with the given Config; the build is separate (build()).
  BvhSphere(std::shared_ptr<const P> prims, const Config& config)
      : prims_(std::move(prims)), config_(config) {}

  /// Bounds of every primitive.
  AABB bounds() const override { return prims_->bounds(); }
  /// The sphere nodes (for tests).
  const SphereNodeArray& nodes() const { return nodes_; }
  /// Primitive ids in leaf order (for tests).
  const std::vector<uint32_t>& order() const { return order_; }

  /// Closest hit: the binary walk with the sphere test; a child is skipped only when its entry distance is
  /// strictly greater than min(tmax, best.t).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if (nodes_.empty()) return;
    const auto limit = [&] { return std::min(ray.tmax, best.t); };
    const auto leaf = [&](uint32_t first, uint32_t count) {
      for (uint32_t k = first, e = first + count; k < e; ++k)
        intersect_leaf_prim<kCount>(k, ray, best, inst, c);
      return false;
    };
    walk_bvh2<kCount, true>(nodes_.data(), ray, limit, leaf, c);
  }

  /// Any hit within [tmin, tmax]: stops at the first primitive that reports one.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    if (nodes_.empty()) return false;
    const auto limit = [&] { return ray.tmax; };
    const auto leaf = [&](uint32_t first, uint32_t count) {
      for (uint32_t k = first, e = first + count; k < e; ++k)
        if (occluded_leaf_prim<kCount>(k, ray, c)) return true;
      return false;
    };
    return walk_bvh2<kCount, false>(nodes_.data(), ray, limit, leaf, c);
  }

 protected:
  /// Builds bvh-sah's binary tree, fits the spheres and drops the boxes.
  void do_build() override {
    BvhBuildResult tree = build_topology();
    order_ = std::move(tree.order);
    if (tree.nodes.empty()) return;
    std::vector<vec3> points;
    std::vector<uint32_t> begin;
    gather_points(points, begin);
    nodes_ = fit_spheres(tree.nodes, {points, begin});
    if constexpr (kCopiesTriangles) {
      tris_.resize(order_.size());
      for (size_t k = 0; k < order_.size(); ++k) tris_[k] = prims_->triangle(order_[k]);
    }
  }

  /// The tree's figures from the one statistics walk, and the bytes of the nodes, ids and triangles.
  void gather_stats(BuildStats& stats) const override {
    stats.primitives = prims_->size();
    if (!nodes_.empty()) walk_tree_stats(SphereTreeVisitor{nodes_}, stats);
    stats.bytes = nodes_.size() * sizeof(SphereNode) + order_.size() * sizeof(uint32_t) +
                  tris_.size() * sizeof(Triangle);
  }

 private:
  static constexpr bool kCopiesTriangles = std::is_same_v<P, TrianglePrims>;

  /// bvh-sah's binary tree over the bounds and centroids of every primitive (gathered in parallel).
  BvhBuildResult build_topology() const {
    const size_t n = prims_->size();
    std::vector<AABB> boxes(n);
    std::vector<vec3> centroids(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        boxes[i] = prims_->bounds(i);
        centroids[i] = prims_->centroid(i);
      }
    });
    return build_bvh(config_.builder(), boxes, centroids);
  }

  /// The points the spheres must hold, in leaf order: a triangle's three vertices, the eight corners of
  /// any other primitive's bounds (none when they are empty).
  void gather_points(std::vector<vec3>& points, std::vector<uint32_t>& begin) const {
    begin.reserve(order_.size() + 1);
    for (const uint32_t id : order_) {
      begin.push_back(uint32_t(points.size()));
      if constexpr (kCopiesTriangles) {
        const Triangle& t = prims_->triangle(id);
        points.insert(points.end(), {t.v0, t.v1, t.v2});
      } else {
        const AABB b = prims_->bounds(id);
        if (b.empty()) continue;
        for (int c = 0; c < 8; ++c)
          points.push_back({(c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z});
      }
    }
    begin.push_back(uint32_t(points.size()));
  }

  /// Tests the k-th primitive of leaf order with the one kernel and the original id.
  template <bool kCount>
  [[gnu::always_inline]] void intersect_leaf_prim(uint32_t k, const Ray& ray, Hit& best, uint32_t inst,
                                                  RayCounters& c) const {
    if constexpr (kCopiesTriangles) {
      if constexpr (kCount) ++c.prims;
      TriangleHit th;  // the id (another cache line) is read only for a hit
      if (intersect_triangle(ray, tris_[k], th)) accept_hit(th, order_[k], inst, best);
    } else {
      prims_->template intersect<kCount>(order_[k], ray, best, inst, c);
    }
  }
  /// Any-hit test of the k-th primitive of leaf order.
  template <bool kCount>
  bool occluded_leaf_prim(uint32_t k, const Ray& ray, RayCounters& c) const {
    if constexpr (kCopiesTriangles) {
      if constexpr (kCount) ++c.prims;
      TriangleHit th;
      return intersect_triangle(ray, tris_[k], th);
    } else {
      return prims_->template occluded<kCount>(order_[k], ray, c);
    }
  }

  std::shared_ptr<const P> prims_;
  Config config_;
  SphereNodeArray nodes_;        ///< the sphere tree (root at 0, padding at 1, sibling pairs)
  std::vector<uint32_t> order_;  ///< primitive ids in leaf order
  std::vector<Triangle> tris_;   ///< triangles in leaf order (TrianglePrims)
};

}  // namespace ab
