// Bounding volume hierarchies over any primitive set: object median (bvh-median), binned SAH (bvh-sah,
// Wald 2007) and full-sweep SAH (bvh-sweep, MacDonald and Booth 1990). All three build one depth-first
// array of 32-byte binary nodes traversed with an explicit stack, nearer child first (`width=2`, the default
// of bvh-median and bvh-sweep); with `width=8` (bvh-sah's default) that tree is collapsed into an 8-wide
// BVH whose child boxes are tested at once with AVX2 (bvh_wide.h).
#pragma once

#include "accel/core/box_test.h"
#include "accel/core/accelerator.h"
#include "accel/bvh/node.h"
#include "accel/bvh/wide.h"
#include "accel/core/params.h"
#include "accel/core/primitives.h"
#include "accel/common/sah.h"
#include "accel/core/triangle4.h"

#include <tbb/parallel_for.h>


#include <cstdint>
#include <memory>
#include <new>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace ab {

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
  int bins = 32;                     ///< binned SAH: bins per axis
  SahCosts costs;                    ///< SAH traversal and intersection costs
  size_t parallel_threshold = 4096;  ///< subtrees at least this large build their children in parallel
};

/// What the builder produces: the node array, the leaf order of primitive ids and the statistics
/// (nodes, leaves, depths, histogram, references, SAH cost; bytes are left to the structure).
struct BvhBuildResult {
  BvhNodeArray nodes;
  std::vector<uint32_t> order;
  BuildStats stats;
};

/// Builds a BVH over primitives given by their bounds and centroids. Deterministic: the same tree for
/// any number of threads. Implemented in bvh.cpp, bvh_binned.cpp and bvh_sweep.cpp (not a template: the
/// primitive set is not needed). The binned builder bins the centres of the bounds, which is what both
/// primitive sets' centroid() returns; the median and sweep builders use `centroids`.
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
      : prims_(std::move(prims)), config_(read_bvh_config(M, params)), width_(read_width(params)),
        effective_(params.effective()) {
    // Wide leaves test triangles four at a time, so the SAH prices a leaf by its blocks of four.
    if (width_ == 8 && kCopiesTriangles) config_.costs.block = 4;
  }

  std::string name() const override { return bvh_method_name(M); }
  nlohmann::json config() const override { return effective_; }
  AABB bounds() const override { return prims_->bounds(); }
  /// The flattened binary nodes (empty for width 8, whose build frees them; for tests).
  const BvhNodeArray& nodes() const { return nodes_; }
  /// The 8-wide nodes (empty for width 2; for tests).
  const Bvh8NodeArray& wide_nodes() const { return wide_; }
  /// Original ids of the wide leaves' triangle block lanes (kInvalidId for padding; for tests).
  const std::vector<uint32_t>& block_ids() const { return block_ids_; }
  /// Primitive ids in leaf order (for tests).
  const std::vector<uint32_t>& order() const { return order_; }

  /// Closest hit: depth-first, nearer child first (both child boxes tested at once); a child is skipped only when its entry distance is
  /// strictly greater than best.t (the box test's upper bound is min(tmax, best.t)).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if (width_ == 8) {
      if (wide_.empty()) return;
      const LeafRay leaf_ray(ray);
      walk_bvh8<kCount, true>(
          wide_.data(), ray, [&] { return std::min(ray.tmax, best.t); },
          [&](uint32_t first, uint32_t count) { return wide_leaf<kCount, false>(first, count, ray, leaf_ray, &best, inst, c); },
          leaf_data(), sizeof(Triangle4), c);
      return;
    }
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
    if (width_ == 8) {
      if (wide_.empty()) return false;
      const LeafRay leaf_ray(ray);
      return walk_bvh8<kCount, false>(
          wide_.data(), ray, [&] { return ray.tmax; },
          [&](uint32_t first, uint32_t count) { return wide_leaf<kCount, true>(first, count, ray, leaf_ray, nullptr, 0, c); },
          leaf_data(), sizeof(Triangle4), c);
    }
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
    this->stats_.extra["width"] = width_;
    if (width_ == 8) {
      wide_ = collapse_to_bvh8(nodes_, this->stats_);
      BvhNodeArray().swap(nodes_);
    }
    if constexpr (kCopiesTriangles) {
      if (width_ == 8) {
        pack_leaf_blocks();
      } else {
        tris_.resize(order_.size());
        for (size_t k = 0; k < order_.size(); ++k) tris_[k] = prims_->triangle(order_[k]);
      }
    }
    this->stats_.bytes = nodes_.size() * sizeof(BvhNode) + wide_.size() * sizeof(Bvh8Node) +
                         order_.size() * sizeof(uint32_t) + tris_.size() * sizeof(Triangle) +
                         blocks_.size() * sizeof(Triangle4) + block_ids_.size() * sizeof(uint32_t);
  }

 private:
  static constexpr bool kCopiesTriangles = std::is_same_v<P, TrianglePrims>;

  /// What a wide leaf is tested with: the ray broadcast to four lanes for triangle blocks, else the ray.
  using LeafRay = std::conditional_t<kCopiesTriangles, Ray4, Ray>;

  /// The wide tree's triangle blocks as bytes for prefetching (null for other primitive sets).
  const char* leaf_data() const { return blocks_.empty() ? nullptr : reinterpret_cast<const char*>(blocks_.data()); }

  /// Replaces each wide leaf's primitive range by blocks of four triangles (Embree's Triangle4 layout):
  /// lane child = first block, count unchanged; ids per lane (kInvalidId for padding). order_ is then
  /// no longer needed.
  void pack_leaf_blocks() {
    for (Bvh8Node& node : wide_) {
      for (int k = 0; k < Bvh8Node::kWidth; ++k) {
        if (node.count[k] == 0) continue;
        const uint32_t first = node.child[k], n = node.count[k];
        node.child[k] = uint32_t(blocks_.size());
        for (uint32_t s = 0; s < n; s += 4) {
          Triangle quad[4];
          const uint32_t m = std::min(4u, n - s);
          for (uint32_t j = 0; j < 4; ++j) {
            if (j < m) quad[j] = prims_->triangle(order_[first + s + j]);
            block_ids_.push_back(j < m ? order_[first + s + j] : kInvalidId);
          }
          blocks_.push_back(Triangle4::pack(std::span<const Triangle>(quad, m)));
        }
      }
    }
    std::vector<uint32_t>().swap(order_);
  }

  /// Tests a wide leaf (`first`, `count` as stored in its lane): triangle blocks four at a time with the
  /// one kernel, other primitives one by one. kAny: returns true at the first hit; otherwise updates *best
  /// and returns false.
  template <bool kCount, bool kAny>
  [[gnu::always_inline]] bool wide_leaf(uint32_t first, uint32_t count, const Ray& ray, const LeafRay& leaf_ray,
                                        Hit* best, uint32_t inst, RayCounters& c) const {
    if constexpr (kCopiesTriangles) {
      if constexpr (kCount) c.prims += count;
      for (uint32_t b = first, e = first + (count + 3) / 4; b < e; ++b) {
        alignas(16) float t[4], u[4], v[4];
        unsigned mask = intersect_triangle4(leaf_ray, blocks_[b], t, u, v);
        if constexpr (kAny) {
          if (mask) return true;
        } else {
          for (; mask; mask &= mask - 1) {
            const int j = std::countr_zero(mask);
            accept_hit({t[j], u[j], v[j]}, block_ids_[4 * b + j], inst, *best);
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

  /// Node width: 2 (the binary tree) or 8 (collapsed); bvh-sah defaults to 8, the others to 2.
  static int read_width(Params& params) {
    const int w = int(params.get_int("width", M == BvhMethod::kBinnedSah ? 8 : 2, 2, 8));
    if (w != 2 && w != 8) throw ParamError("parameter 'width': " + std::to_string(w) + " is not 2 or 8");
    return w;
  }

  /// Tests the k-th primitive of leaf order with the one kernel and the original id.
  template <bool kCount>
  [[gnu::always_inline]] void intersect_leaf_prim(uint32_t k, const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
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
  BvhConfig config_;
  int width_;
  nlohmann::json effective_;
  BvhNodeArray nodes_;
  Bvh8NodeArray wide_;
  std::vector<uint32_t> order_;
  std::vector<Triangle> tris_;  ///< triangles in leaf order (TrianglePrims, width 2)
  std::vector<Triangle4> blocks_;     ///< wide leaves' triangles, four per block (TrianglePrims, width 8)
  std::vector<uint32_t> block_ids_;   ///< original id of each block lane (kInvalidId for padding)
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
