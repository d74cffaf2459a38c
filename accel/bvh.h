// Binary bounding volume hierarchies over any primitive set: object median (bvh-median), binned SAH
// (bvh-sah, Wald 2007) and full-sweep SAH (bvh-sweep, MacDonald and Booth 1990). All three flatten into
// one depth-first array of 32-byte nodes traversed with an explicit stack, nearer child first.
#pragma once

#include "accel/accelerator.h"
#include "accel/params.h"
#include "accel/primitives.h"
#include "accel/sah.h"

#include <tbb/parallel_for.h>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace ab {

/// One flattened BVH node. Interior (count == 0): the left child is the next node, the right child is
/// `offset`. Leaf (count > 0): primitives [offset, offset + count) of the leaf-ordered reference array.
/// The layout (lo, offset, hi, count) lets a box load as two 16-byte vectors.
struct alignas(32) BvhNode {
  float lo[3];
  uint32_t offset;
  float hi[3];
  uint32_t count;

  /// True for a leaf.
  bool is_leaf() const { return count > 0; }
  /// The node's box.
  AABB box() const { return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}}; }
};
static_assert(sizeof(BvhNode) == 32, "BVH nodes are 32 bytes");

/// How a BVH chooses its splits.
enum class BvhMethod {
  kMedian,     ///< object median of centroids along the longest axis of the centroid bounds
  kBinnedSah,  ///< binned SAH on all three axes (Wald 2007)
  kSweepSah,   ///< full sweep SAH over sorted centroids on all three axes
};

/// Build settings of every BVH variant (fields a method does not use are ignored).
struct BvhConfig {
  int max_leaf_size = 4;             ///< median: leaf size; SAH: a node above this size is always split
  int max_depth = 64;                ///< a node at this depth becomes a leaf
  int bins = 16;                     ///< binned SAH: bins per axis
  SahCosts costs;                    ///< SAH traversal and intersection costs
  size_t parallel_threshold = 4096;  ///< subtrees at least this large build their children in parallel
};

/// Largest allowed max_depth (the traversal stack holds one entry per level).
inline constexpr int kBvhMaxDepth = 120;

/// What the builder produces: the node array, the leaf order of primitive ids and the statistics
/// (nodes, leaves, depths, histogram, references, SAH cost; bytes are left to the structure).
struct BvhBuildResult {
  std::vector<BvhNode> nodes;
  std::vector<uint32_t> order;
  BuildStats stats;
};

/// Builds a BVH over primitives given by their bounds and centroids. Deterministic: the same tree for
/// any number of threads. Implemented in bvh.cpp (not a template: the primitive set is not needed).
BvhBuildResult build_bvh(BvhMethod method, const BvhConfig& config, std::span<const AABB> bounds,
                         std::span<const vec3> centroids);

/// Registry name of a method.
const char* bvh_method_name(BvhMethod method);

/// Reads a BvhConfig for `method` from params (strict ranges; effective values recorded).
BvhConfig read_bvh_config(BvhMethod method, Params& params);

/// Entry distance of the ray into node n's box, clipped to [t0, t1]; +inf when it misses. Same
/// arithmetic as slab_test (widened both ends), with the near/far planes selected by the sign bits.
inline float bvh_node_entry(const BvhNode& n, const RayBoxData& r, float t0, float t1) {
  const float* planes = n.lo;  // lo at 0..2, hi at 4..6
  for (int a = 0; a < 3; ++a) {
    const float tn = widen_near((planes[a + 4 * r.neg[a]] - r.org[a]) * r.inv_dir[a]);
    const float tf = widen_far((planes[a + 4 * (1 - r.neg[a])] - r.org[a]) * r.inv_dir[a]);
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  return t0 <= t1 ? t0 : kInf;
}

/// A BVH over primitive set P built by `M`. For triangles the vertices are copied into leaf order
/// for locality; hits still carry the original ids.
template <class P, BvhMethod M>
class Bvh final : public AcceleratorBase<Bvh<P, M>> {
 public:
  /// Reads the Config from params; the build is separate (build()).
  Bvh(std::shared_ptr<const P> prims, Params& params)
      : prims_(std::move(prims)), config_(read_bvh_config(M, params)), effective_(params.effective()) {}

  std::string name() const override { return bvh_method_name(M); }
  nlohmann::json config() const override { return effective_; }
  AABB bounds() const override { return prims_->bounds(); }
  /// The flattened nodes (for tests).
  const std::vector<BvhNode>& nodes() const { return nodes_; }
  /// Primitive ids in leaf order (for tests).
  const std::vector<uint32_t>& order() const { return order_; }

  /// Closest hit: depth-first, nearer child first; a child is skipped only when its entry distance is
  /// strictly greater than best.t (the box test's upper bound is min(tmax, best.t)).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if (nodes_.empty()) return;
    const RayBoxData rd(ray);
    const BvhNode* nodes = nodes_.data();
    if (bvh_node_entry(nodes[0], rd, ray.tmin, std::min(ray.tmax, best.t)) == kInf) return;
    struct Entry {
      uint32_t node;
      float t;
    };
    Entry stack[kBvhMaxDepth + 2];
    int sp = 0;
    uint32_t idx = 0;
    for (;;) {
      const BvhNode& n = nodes[idx];
      if constexpr (kCount) ++c.nodes;
      if (!n.is_leaf()) {
        const float limit = std::min(ray.tmax, best.t);
        const uint32_t l = idx + 1, r = n.offset;
        const float tl = bvh_node_entry(nodes[l], rd, ray.tmin, limit);
        const float tr = bvh_node_entry(nodes[r], rd, ray.tmin, limit);
        if (tl != kInf && tr != kInf) {
          const bool left_first = tl <= tr;
          idx = left_first ? l : r;
          stack[sp++] = {left_first ? r : l, left_first ? tr : tl};
          continue;
        }
        if (tl != kInf || tr != kInf) {
          idx = tl != kInf ? l : r;
          continue;
        }
      } else {
        if constexpr (kCount) ++c.leaves;
        for (uint32_t k = n.offset, e = n.offset + n.count; k < e; ++k) intersect_leaf_prim<kCount>(k, ray, best, inst, c);
      }
      do {
        if (sp == 0) return;
        --sp;
      } while (stack[sp].t > best.t);
      idx = stack[sp].node;
    }
  }

  /// Any hit within [tmin, tmax]: stops at the first primitive that reports one.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    if (nodes_.empty()) return false;
    const RayBoxData rd(ray);
    const BvhNode* nodes = nodes_.data();
    if (bvh_node_entry(nodes[0], rd, ray.tmin, ray.tmax) == kInf) return false;
    uint32_t stack[kBvhMaxDepth + 2];
    int sp = 0;
    uint32_t idx = 0;
    for (;;) {
      const BvhNode& n = nodes[idx];
      if constexpr (kCount) ++c.nodes;
      if (!n.is_leaf()) {
        const uint32_t l = idx + 1, r = n.offset;
        const float tl = bvh_node_entry(nodes[l], rd, ray.tmin, ray.tmax);
        const float tr = bvh_node_entry(nodes[r], rd, ray.tmin, ray.tmax);
        if (tl != kInf && tr != kInf) {
          idx = tl <= tr ? l : r;
          stack[sp++] = tl <= tr ? r : l;
          continue;
        }
        if (tl != kInf || tr != kInf) {
          idx = tl != kInf ? l : r;
          continue;
        }
      } else {
        if constexpr (kCount) ++c.leaves;
        for (uint32_t k = n.offset, e = n.offset + n.count; k < e; ++k)
          if (occluded_leaf_prim<kCount>(k, ray, c)) return true;
      }
      if (sp == 0) return false;
      idx = stack[--sp];
    }
  }

 protected:
  void do_build() override {
    const size_t n = prims_->size();
    std::vector<AABB> boxes(n);
    std::vector<vec3> centroids(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        boxes[i] = prims_->bounds(i);
        centroids[i] = prims_->centroid(i);
      }
    });
    BvhBuildResult result = build_bvh(M, config_, boxes, centroids);
    nodes_ = std::move(result.nodes);
    order_ = std::move(result.order);
    this->stats_ = std::move(result.stats);
    this->stats_.bytes = nodes_.size() * sizeof(BvhNode) + order_.size() * sizeof(uint32_t);
    if constexpr (kCopiesTriangles) {
      tris_.resize(order_.size());
      for (size_t k = 0; k < order_.size(); ++k) tris_[k] = prims_->triangle(order_[k]);
      this->stats_.bytes += tris_.size() * sizeof(Triangle);
    }
  }

 private:
  static constexpr bool kCopiesTriangles = std::is_same_v<P, TrianglePrims>;

  /// Tests the k-th primitive of leaf order with the one kernel and the original id.
  template <bool kCount>
  void intersect_leaf_prim(uint32_t k, const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if constexpr (kCopiesTriangles) {
      if constexpr (kCount) ++c.prims;
      intersect_and_update(ray, tris_[k], order_[k], inst, best);
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
  BvhConfig config_;
  nlohmann::json effective_;
  std::vector<BvhNode> nodes_;
  std::vector<uint32_t> order_;
  std::vector<Triangle> tris_;  ///< triangles in leaf order (TrianglePrims only)
};

/// Object-median BVH (registered as bvh-median).
template <class P>
using BvhMedian = Bvh<P, BvhMethod::kMedian>;
/// Binned-SAH BVH (registered as bvh-sah).
template <class P>
using BvhSah = Bvh<P, BvhMethod::kBinnedSah>;
/// Full-sweep SAH BVH (registered as bvh-sweep).
template <class P>
using BvhSweep = Bvh<P, BvhMethod::kSweepSah>;

}  // namespace ab
