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
#include <new>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace ab {

/// One flattened BVH node. Interior (count == 0): the children are the sibling pair `offset`, `offset + 1`
/// (one 64-byte line, so one fetch gives both boxes for the two-box test). Leaf (count > 0): primitives
/// [offset, offset + count) of the leaf-ordered reference array. The layout (lo, offset, hi, count) lets
/// a node load as one 32-byte vector. Node 0 is the root, node 1 is padding, pairs start at 2.
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

/// Allocator aligning the node array to 64 bytes, so each sibling pair shares one cache line.
template <class T>
struct CacheLineAllocator {
  using value_type = T;
  CacheLineAllocator() = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) {}
  T* allocate(size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(64))); }
  void deallocate(T* p, size_t) { ::operator delete(p, std::align_val_t(64)); }
  bool operator==(const CacheLineAllocator&) const { return true; }
};

/// The node array of a BVH.
using BvhNodeArray = std::vector<BvhNode, CacheLineAllocator<BvhNode>>;

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
  BvhNodeArray nodes;
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

/// Entry distances of a ray into the two nodes of a sibling pair (+inf for a miss), clipped to
/// [tmin, limit]. The arithmetic is slab_test's: per-axis distances (plane - org) * inv_dir with the planes
/// chosen by the direction's sign, NaN ignored; the widening is applied once to the reduced near and far
/// distance, which equals widening every axis first because widening is monotonic. (A 256-bit version
/// testing both boxes at once measured slower on this machine than this scalar one.)
struct BvhPairTest {
  explicit BvhPairTest(const Ray& ray) : rd(ray), tmin(ray.tmin) {
    for (int a = 0; a < 3; ++a) {
      near_index[a] = a + 4 * rd.neg[a];
      far_index[a] = a + 4 * (1 - rd.neg[a]);
    }
  }

  /// Entry of one node.
  [[gnu::always_inline]] float entry(const BvhNode& n, float limit) const {
    const float* p = n.lo;  // lo at 0..2, hi at 4..6
    float tn = -kInf, tf = kInf;
    for (int a = 0; a < 3; ++a) {
      const float near_t = (p[near_index[a]] - rd.org[a]) * rd.inv_dir[a];
      const float far_t = (p[far_index[a]] - rd.org[a]) * rd.inv_dir[a];
      tn = near_t > tn ? near_t : tn;
      tf = far_t < tf ? far_t : tf;
    }
    const float t0 = std::max(widen_near(tn), tmin);
    const float t1 = std::min(widen_far(tf), limit);
    return t0 <= t1 ? t0 : kInf;
  }
  /// Entries of pair[0] and pair[1] into tl and tr.
  [[gnu::always_inline]] void entries(const BvhNode* pair, float limit, float& tl, float& tr) const {
    tl = entry(pair[0], limit);
    tr = entry(pair[1], limit);
  }

  RayBoxData rd;                      ///< origin, reciprocal direction, sign bits
  float tmin;                         ///< the ray's tmin (lower clip of every entry)
  int near_index[3], far_index[3];    ///< float index in a node of the near and far plane per axis
};

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
  const BvhNodeArray& nodes() const { return nodes_; }
  /// Primitive ids in leaf order (for tests).
  const std::vector<uint32_t>& order() const { return order_; }

  /// Closest hit: depth-first, nearer child first (both child boxes tested at once); a child is skipped only when its entry distance is
  /// strictly greater than best.t (the box test's upper bound is min(tmax, best.t)).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if (nodes_.empty()) return;
    const BvhPairTest test(ray);
    const BvhNode* nodes = nodes_.data();
    if (test.entry(nodes[0], std::min(ray.tmax, best.t)) == kInf) return;
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
        const uint32_t l = n.offset, r = n.offset + 1;
        float tl, tr;
        test.entries(nodes + l, std::min(ray.tmax, best.t), tl, tr);
        if (tl != kInf && tr != kInf) {
          const bool left_first = tl <= tr;
          idx = left_first ? l : r;
          const uint32_t far = left_first ? r : l;
          stack[sp++] = {far, left_first ? tr : tl};
          if (!nodes[far].is_leaf()) __builtin_prefetch(nodes + nodes[far].offset);
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
    const BvhPairTest test(ray);
    const BvhNode* nodes = nodes_.data();
    if (test.entry(nodes[0], ray.tmax) == kInf) return false;
    uint32_t stack[kBvhMaxDepth + 2];
    int sp = 0;
    uint32_t idx = 0;
    for (;;) {
      const BvhNode& n = nodes[idx];
      if constexpr (kCount) ++c.nodes;
      if (!n.is_leaf()) {
        const uint32_t l = n.offset, r = n.offset + 1;
        float tl, tr;
        test.entries(nodes + l, ray.tmax, tl, tr);
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
  [[gnu::always_inline]] void intersect_leaf_prim(uint32_t k, const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
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
  BvhNodeArray nodes_;
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
