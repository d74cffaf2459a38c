// Bounding volume hierarchies over any primitive set: object median (bvh-median), binned SAH (bvh-sah,
// Wald 2007) and full-sweep SAH (bvh-sweep, MacDonald and Booth 1990). All three build one depth-first
// array of 32-byte binary nodes (build.h) traversed by the binary walk (walk2.h, `width=2`, the default of
// bvh-median and bvh-sweep); with `width=8` (bvh-sah's default) that tree is collapsed (collapse.h) into an
// 8-wide BVH whose child boxes are tested at once with AVX2 (walk8.h).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <memory>
#include <mutex>
#include <type_traits>
#include <vector>

#include "accel/bvh/build.h"
#include "accel/bvh/collapse.h"
#include "accel/bvh/config.h"
#include "accel/bvh/leaf_blocks.h"
#include "accel/bvh/node.h"
#include "accel/bvh/node8.h"
#include "accel/bvh/sbvh.h"
#include "accel/bvh/slots.h"
#include "accel/bvh/tree_visitors.h"
#include "accel/bvh/walk2.h"
#include "accel/bvh/walk8.h"
#include "accel/common/epo.h"
#include "accel/common/huge_pages.h"
#include "accel/common/tree_stats.h"
#include "accel/core/accelerator.h"
#include "accel/core/primitives.h"
#include "accel/core/triangle.h"
#include "accel/core/triangle4.h"

namespace ab {

template <class B>
struct BvhRefit;

/// A BVH over primitive set P built by the builder of its Config C (BvhMedianConfig, BvhSahConfig,
/// BvhSweepConfig or BvhSbvhConfig, whose spatial splits may reference a primitive from several leaves). For
/// triangles the vertices are copied into leaf order for locality (blocks of four for width 8); hits still
/// carry the original ids.
template <class P, class C>
class Bvh final : public AcceleratorBase<Bvh<P, C>> {
 public:
  using Prims = P;   ///< the primitive set
  using Config = C;  ///< the Config, which also chooses the builder (build_bvh's overloads)

  /// Over prims with the given Config; the build is separate (build()).
  Bvh(std::shared_ptr<const P> prims, const Config& config)
      : prims_(std::move(prims)), config_(config), bounds_(prims_->bounds()) {
    // Wide leaves test triangles four at a time, so the SAH prices a leaf by its blocks of four.
    if constexpr (requires { config_.costs; })
      if (config_.width == 8 && kCopiesTriangles) config_.costs.block = 4;
  }

  /// Bounds of every primitive (at the last build or refit).
  AABB bounds() const override { return bounds_; }
  /// The flattened binary nodes (empty for width 8, whose build frees them; for tests).
  const BvhNodeArray& nodes() const { return nodes_; }
  /// The 8-wide nodes (empty for width 2; for tests).
  const Bvh8NodeArray& wide_nodes() const { return wide_; }
  /// Original ids of the wide leaves' triangle block lanes (kInvalidId for padding; for tests).
  const BlockIdArray& block_ids() const { return blocks_.ids; }
  /// Primitive ids in leaf order (for tests).
  const std::vector<uint32_t>& order() const { return order_; }
  /// The wide leaves' triangle blocks (empty for width 2; for tests).
  const Triangle4Array& leaf_blocks() const { return blocks_.blocks; }

  /// Closest hit: front to back, nearer child first; a child is skipped only when its entry distance is
  /// strictly greater than best.t (the box tests' upper bound is min(tmax, best.t)).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    const auto limit = [&] { return std::min(ray.tmax, best.t); };
    if (config_.width == 8) {
      if (wide_.empty()) return;
      const Bvh8RayTest test(ray);
      LeafRay leaf_ray = leaf_ray_of(ray, test.rd);
      const auto leaf = [&](uint32_t first, uint32_t count) {
        return wide_leaf<kCount, false>(first, count, ray, leaf_ray, &best, inst, c);
      };
      walk_bvh8<kCount, true>(wide_.data(), test, ray, limit, leaf, leaf_data(), sizeof(Triangle4), c);
      return;
    }
    if (nodes_.empty()) return;
    walk_bvh2<kCount, true>(
        nodes_.data(), ray, limit,
        [&](uint32_t first, uint32_t count) {
          for (uint32_t k = first, e = first + count; k < e; ++k)
            intersect_leaf_prim<kCount>(k, ray, best, inst, c);
          return false;
        },
        c);
  }

  /// Any hit within [tmin, tmax]: stops at the first primitive that reports one.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    const auto limit = [&] { return ray.tmax; };
    if (config_.width == 8) {
      if (wide_.empty()) return false;
      const Bvh8RayTest test(ray);
      LeafRay leaf_ray = leaf_ray_of(ray, test.rd);
      const auto leaf = [&](uint32_t first, uint32_t count) {
        return wide_leaf<kCount, true>(first, count, ray, leaf_ray, nullptr, 0, c);
      };
      return walk_bvh8<kCount, false>(wide_.data(), test, ray, limit, leaf, leaf_data(), sizeof(Triangle4),
                                      c);
    }
    if (nodes_.empty()) return false;
    return walk_bvh2<kCount, false>(
        nodes_.data(), ray, limit,
        [&](uint32_t first, uint32_t count) {
          for (uint32_t k = first, e = first + count; k < e; ++k)
            if (occluded_leaf_prim<kCount>(k, ray, c)) return true;
          return false;
        },
        c);
  }

 protected:
  /// Refit hooks (refit.h, Wald, Boulos and Shirley 2007).
  bool do_refit_triangles(std::shared_ptr<const TrianglePrims> p) override {
    return BvhRefit<Bvh>::refit(*this, p);
  }
  bool do_refit_instances(std::shared_ptr<const InstancePrims> p) override {
    return BvhRefit<Bvh>::refit(*this, p);
  }
  bool do_refit_mesh(std::shared_ptr<const Mesh> mesh) override {
    if constexpr (kCopiesTriangles) return BvhRefit<Bvh>::refit_mesh(*this, std::move(mesh));
    return false;
  }

  void do_build() override {
    bounds_ = current_prims().bounds();
    if (collapses_from_slots()) {
      build_wide_from_slots();
    } else {
      BvhBuildResult result = build_bvh_over_prims();
      nodes_ = std::move(result.nodes);
      order_ = std::move(result.order);
      if (config_.width == 8) collapse();
    }
    if constexpr (kCopiesTriangles) {
      if (config_.width == 8) {
        blocks_ = pack_leaf_blocks(wide_, order_, *prims_);
        std::vector<uint32_t>().swap(order_);  // the blocks carry the ids
      } else {
        tris_.resize(order_.size());
        for (size_t k = 0; k < order_.size(); ++k) tris_[k] = prims_->triangle(order_[k]);
      }
    }
  }

  /// The tree's figures from the one statistics walk; for width 8 the wide tree's, with the binary tree's
  /// node count, depth and SAH cost (sah_cost stays the binary tree's, comparable with bvh-sweep's) taken
  /// before the collapse.
  void gather_stats(BuildStats& stats) const override {
    stats.primitives = prims_->size();
    if (!nodes_.empty()) walk_tree_stats(BvhTreeVisitor{nodes_}, stats);
    if (!wide_.empty()) {
      walk_tree_stats(Bvh8TreeVisitor{wide_}, stats);
      stats.extra["binary_nodes"] = binary_.nodes;
      stats.extra["binary_max_depth"] = binary_.max_depth;
      stats.extra["wide_sah_cost"] = stats.sah_cost;
      stats.extra["mean_children"] = mean_children(wide_);
      stats.sah_cost = binary_.sah_cost;
    }
    stats.extra["width"] = config_.width;
    stats.bytes = nodes_.size() * sizeof(BvhNode) + wide_.size() * sizeof(Bvh8Node) +
                  order_.size() * sizeof(uint32_t) + tris_.size() * sizeof(Triangle) +
                  blocks_.blocks.size() * sizeof(Triangle4) + blocks_.ids.size() * sizeof(uint32_t);
  }

  /// The end-point overlap of the tree as traversed (over triangles only).
  void gather_quality(BuildStats& stats) const override {
    if constexpr (kCopiesTriangles) stats.epo = tree_epo();
  }

 private:
  friend struct BvhRefit<Bvh>;
  static constexpr bool kCopiesTriangles = std::is_same_v<P, TrianglePrims>;
  /// The spatial-split builder clips primitives, so it gets their clipped bounds too (sbvh.h).
  static constexpr bool kSpatialSplits = std::is_same_v<C, BvhSbvhConfig>;

  /// What a wide leaf is tested with: the ray broadcast to four lanes for triangle blocks, else the ray.
  using LeafRay = std::conditional_t<kCopiesTriangles, Ray4, Ray>;
  /// The leaf ray of ray, sharing rd = RayBoxData(ray) (the walk's box test's) for the blocks' acceptance.
  static LeafRay leaf_ray_of(const Ray& ray, const RayBoxData& rd) {
    if constexpr (kCopiesTriangles) {
      return Ray4(ray, rd);
    } else {
      return ray;
    }
  }

  /// Calls build(bounds, centroids) with the bounds and centroids of every primitive, gathered in parallel
  /// into uninitialized arrays (the binned and spatial-split builders read no centroids, so they get none).
  template <class F>
  auto over_prim_bounds(F&& build) const {
    constexpr bool kCentroids = !kSpatialSplits && !std::is_same_v<C, BvhSahConfig>;
    const size_t n = prims_->size();
    const LargeArray<AABB> boxes(n);
    const LargeArray<vec3> centroids(kCentroids ? n : 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        boxes[i] = prims_->bounds(i);
        if constexpr (kCentroids) centroids[i] = prims_->centroid(i);
      }
    });
    return build(std::span<const AABB>(boxes.get(), n),
                 std::span<const vec3>(centroids.get(), centroids.size()));
  }

  /// Runs the Config's builder over the bounds and centroids of every primitive.
  BvhBuildResult build_bvh_over_prims() const {
    return over_prim_bounds([&](std::span<const AABB> bounds, std::span<const vec3> centroids) {
      if constexpr (kSpatialSplits)
        return build_bvh(config_, bounds,
                         [&](uint32_t i, const AABB& box) { return prims_->clipped_bounds(i, box); });
      else
        return build_bvh(config_, bounds, centroids);
    });
  }

  /// True when the wide tree is the collapse of a binned build, which collapses straight from the builder's
  /// slots (no flattened binary tree).
  bool collapses_from_slots() const {
    if constexpr (std::is_same_v<C, BvhSahConfig>) return config_.width == 8;
    return false;
  }

  /// The binned build collapsed from its slots, keeping the binary tree's figures for the report
  /// (the statistics walk sees the slots' tree as it would see the flattened one).
  void build_wide_from_slots() {
    if constexpr (std::is_same_v<C, BvhSahConfig>) {
      // The primitives' bounds go straight into the builder's references (no array of all the bounds).
      BvhSlotsResult built =
          build_bvh_slots(config_, prims_->size(), [&](size_t begin, size_t end, AABB* out) {
            for (size_t i = begin; i < end; ++i) out[i - begin] = prims_->bounds(i);
          });
      order_ = std::move(built.order);
      binary_ = BuildStats{};
      // Both passes only read the slots, so the statistics walk and the collapse run side by side.
      tbb::parallel_invoke(
          [&] {
            if (built.slots.size > 0) walk_tree_stats(BvhSlotsVisitor{built.slots}, binary_);
          },
          [&] { wide_ = collapse_to_bvh8(built.slots, config_.collapse); });
      BvhNodeArray().swap(nodes_);
    }
  }

  /// Replaces the binary tree by its 8-wide collapse, keeping the binary tree's figures for the report.
  void collapse() {
    binary_ = BuildStats{};
    if (!nodes_.empty()) walk_tree_stats(BvhTreeVisitor{nodes_}, binary_);
    if constexpr (requires { config_.collapse; })
      wide_ = collapse_to_bvh8(nodes_, config_.collapse);
    else
      wide_ = collapse_to_bvh8(nodes_);
    BvhNodeArray().swap(nodes_);
  }

  /// End-point overlap (accel/common/epo.h) of the tree as traversed: the binary tree for width 2, the
  /// wide tree for width 8 (its leaves' triangles from the block lanes).
  double tree_epo() const {
    const P& prims = current_prims();
    const auto triangle = [&](size_t id) { return prims.triangle(id); };
    if (!nodes_.empty()) {
      const auto leaf = [&](uint32_t i, auto&& f) {
        for (uint32_t k = nodes_[i].offset; k < nodes_[i].offset + nodes_[i].count; ++k) f(order_[k]);
      };
      return end_point_overlap(BvhTreeVisitor{nodes_}, leaf, prims.size(), triangle);
    }
    if (wide_.empty()) return -1.0;
    const auto leaf = [&](const Bvh8TreeVisitor::Node& n, auto&& f) {
      for (uint32_t k = 4 * n.child; k < 4 * (n.child + (n.count + 3) / 4); ++k)
        if (blocks_.ids[k] != kInvalidId) f(blocks_.ids[k]);
    };
    return end_point_overlap(Bvh8TreeVisitor{wide_}, leaf, prims.size(), triangle);
  }

  /// The wide tree's triangle blocks as bytes for prefetching (null for other primitive sets).
  const char* leaf_data() const {
    return blocks_.blocks.empty() ? nullptr : reinterpret_cast<const char*>(blocks_.blocks.data());
  }

  /// Tests a wide leaf (`first`, `count` as stored in its lane): triangle blocks four at a time with the
  /// one kernel, other primitives one by one. kAny: returns true at the first hit; otherwise updates *best
  /// and returns false. The closest-hit search lowers leaf_ray's tmax to the best hit's t (Ray4::set_tmax).
  template <bool kCount, bool kAny>
  [[gnu::always_inline]] bool wide_leaf(uint32_t first, uint32_t count, const Ray& ray, LeafRay& leaf_ray,
                                        Hit* best, uint32_t inst, RayCounters& c) const {
    if constexpr (kCopiesTriangles) {
      if constexpr (kCount) c.prims += count;
      for (uint32_t b = first, e = first + (count + 3) / 4; b < e; ++b) {
        if constexpr (!kAny) leaf_ray.set_tmax(best->t);
        alignas(16) float t[4], u[4], v[4];
        unsigned mask = intersect_triangle4(leaf_ray, blocks_.blocks[b], t, u, v);
        if constexpr (kAny) {
          if (mask) return true;
        } else {
          for (; mask; mask &= mask - 1) {
            const int j = std::countr_zero(mask);
            accept_hit({t[j], u[j], v[j]}, blocks_.ids[4 * b + j], inst, *best);
          }
        }
      }
    } else {
      for (uint32_t k = first, e = first + count; k < e; ++k) {
        if constexpr (kAny) {
          if (prims_->template occluded<kCount>(order_[k], ray, c)) return true;
        } else {
          prims_->template intersect<kCount>(order_[k], ray, *best, inst, c);
        }
      }
    }
    return false;
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

  /// The primitive set of the current positions: after a refit from a frame's mesh (refit.h) its
  /// TrianglePrims is made here, on first use (the traversal reads only the leaves' copies).
  const P& current_prims() const {
    if constexpr (kCopiesTriangles) {
      const std::lock_guard<std::mutex> lock(frame_mutex_);
      if (frame_mesh_) prims_ = std::make_shared<const P>(std::move(frame_mesh_));
      frame_mesh_.reset();
    }
    return *prims_;
  }

  mutable std::shared_ptr<const P> prims_;  ///< the primitives (of an earlier frame while frame_mesh_)
  mutable std::shared_ptr<const Mesh> frame_mesh_;  ///< the mesh of the last refit_mesh, until current_prims
  mutable std::mutex frame_mutex_;                  ///< guards prims_ and frame_mesh_ in current_prims
  Config config_;
  AABB bounds_;                  ///< bounds of every primitive (the last build's or refit's)
  BvhNodeArray nodes_;           ///< the binary tree (width 2)
  Bvh8NodeArray wide_;           ///< the 8-wide tree (width 8)
  BuildStats binary_;            ///< the binary tree's figures (width 8; taken before the collapse)
  std::vector<uint32_t> order_;  ///< primitive ids in leaf order (freed for width 8 over triangles)
  std::vector<Triangle> tris_;   ///< triangles in leaf order (TrianglePrims, width 2)
  Bvh8LeafBlocks blocks_;        ///< wide leaves' triangles, four per block (TrianglePrims, width 8)
};

/// Object-median BVH (registered as bvh-median).
template <class P>
using BvhMedian = Bvh<P, BvhMedianConfig>;
/// Binned-SAH BVH (registered as bvh-sah).
template <class P>
using BvhSah = Bvh<P, BvhSahConfig>;
/// Full-sweep SAH BVH (registered as bvh-sweep).
template <class P>
using BvhSweep = Bvh<P, BvhSweepConfig>;
/// Binned SAH BVH with spatial splits (registered as bvh-sbvh).
template <class P>
using BvhSbvh = Bvh<P, BvhSbvhConfig>;

}  // namespace ab

#include "accel/bvh/refit.h"  // the refit the hooks above call (it needs Bvh complete)
