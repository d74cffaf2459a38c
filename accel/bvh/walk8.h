// The one walk of the 8-wide BVH, for closest hit and any hit alike: a ray tests the eight child boxes of a
// node at once with AVX2 (Wald, Benthin and Boulos 2008, "Getting rid of packets: efficient SIMD single-ray
// traversal using multi-branching BVHs"), with the same box arithmetic as the binary test (BvhPairTest),
// lane by lane, so both find exactly the same boxes.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

#include "accel/bvh/node.h"
#include "accel/bvh/node8.h"
#include "accel/common/traversal_stack.h"
#include "accel/core/box_test.h"
#include "accel/core/ray.h"
#include "accel/core/stats.h"

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace ab {

/// Entry distances of one ray into the eight boxes of a node, clipped to [tmin, limit]; a lane's bit in
/// the returned mask is set when the ray enters that box. The per-lane arithmetic is BvhPairTest::entry's:
/// (plane - org) * inv_dir with planes chosen by the direction's sign, reductions that keep the bound on
/// NaN, widen_near / widen_far, then the clip.
struct Bvh8RayTest {
  /// Prepares the per-ray data of the box tests (broadcast to eight lanes with AVX2).
  explicit Bvh8RayTest(const Ray& ray) : rd(ray), tmin(ray.tmin) {
    for (int a = 0; a < 3; ++a) {
      near_row[a] = a + 3 * rd.neg[a];
      far_row[a] = a + 3 * (1 - rd.neg[a]);
    }
#if defined(__AVX2__)
    for (int a = 0; a < 3; ++a) {
      org[a] = _mm256_set1_ps(rd.org[a]);
      inv[a] = _mm256_set1_ps(rd.inv_dir[a]);
    }
    tmin8 = _mm256_set1_ps(tmin);
#endif
  }

  /// Entry distances into t[0..7]; returns the mask of lanes entered.
  [[gnu::always_inline]] unsigned entries(const Bvh8Node& n, float limit, float* t) const {
#if defined(__AVX2__)
    __m256 tn = _mm256_set1_ps(-kInf), tf = _mm256_set1_ps(kInf);
    for (int a = 0; a < 3; ++a) {
      const __m256 near_t =
          _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(n.bounds[near_row[a]]), org[a]), inv[a]);
      const __m256 far_t = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(n.bounds[far_row[a]]), org[a]), inv[a]);
      tn = _mm256_max_ps(near_t, tn);  // near_t > tn ? near_t : tn (keeps tn on NaN)
      tf = _mm256_min_ps(far_t, tf);   // far_t < tf ? far_t : tf
    }
    const __m256 zero = _mm256_setzero_ps(), shrink = _mm256_set1_ps(1.0f - kBoxEps),
                 grow = _mm256_set1_ps(1.0f + kBoxEps);
    tn = _mm256_mul_ps(tn, _mm256_blendv_ps(grow, shrink, _mm256_cmp_ps(tn, zero, _CMP_GT_OQ)));
    tf = _mm256_mul_ps(tf, _mm256_blendv_ps(shrink, grow, _mm256_cmp_ps(tf, zero, _CMP_GT_OQ)));
    const __m256 t0 = _mm256_max_ps(tn, tmin8);
    const __m256 t1 = _mm256_min_ps(tf, _mm256_set1_ps(limit));
    _mm256_storeu_ps(t, t0);
    return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ)));
#else
    return entries_scalar(n, limit, t);
#endif
  }

  /// The same computation one lane at a time (the portable path, and the reference in tests).
  unsigned entries_scalar(const Bvh8Node& n, float limit, float* t) const {
    unsigned mask = 0;
    for (int k = 0; k < Bvh8Node::kWidth; ++k) {
      float tn = -kInf, tf = kInf;
      for (int a = 0; a < 3; ++a) {
        const float near_t = (n.bounds[near_row[a]][k] - rd.org[a]) * rd.inv_dir[a];
        const float far_t = (n.bounds[far_row[a]][k] - rd.org[a]) * rd.inv_dir[a];
        tn = near_t > tn ? near_t : tn;
        tf = far_t < tf ? far_t : tf;
      }
      const float wn = widen_near(tn), wf = widen_far(tf);
      t[k] = wn > tmin ? wn : tmin;
      const float t1 = wf < limit ? wf : limit;
      if (t[k] <= t1) mask |= 1u << k;
    }
    return mask;
  }

  RayBoxData rd;                ///< origin, reciprocal direction, sign bits
  float tmin;                   ///< the ray's tmin (lower clip of every entry)
  int near_row[3], far_row[3];  ///< bounds row of the near and far plane per axis
#if defined(__AVX2__)
  __m256 org[3], inv[3], tmin8;  ///< origin, reciprocal direction and tmin in every lane
#endif
};

/// Asks for the cache lines of `bytes` bytes at p ahead of their use (the walk is bound by memory).
[[gnu::always_inline]] inline void prefetch_bytes(const char* p, size_t bytes) {
  for (size_t line = 0; line < bytes; line += 64) __builtin_prefetch(p + line);
}
/// Prefetches a whole node (four lines).
[[gnu::always_inline]] inline void prefetch_node(const Bvh8Node* n) {
  prefetch_bytes(reinterpret_cast<const char*>(n), sizeof(Bvh8Node));
}

/// A child waiting on the 8-wide walk's stack: a node (count 0) or a leaf's range, and the distance at
/// which the ray enters its box.
struct Bvh8StackEntry {
  uint32_t child, count;  ///< as in Bvh8Node's lane
  float t;                ///< entry distance

  /// The entry distance (what TraversalStack prunes by).
  float entry() const { return t; }
};

/// The 8-wide walk's stack: at most seven children wait per level.
using Bvh8Stack = TraversalStack<Bvh8StackEntry, 7 * kBvhMaxDepth + 8>;

/// Stacks the children of node n entered by lane k and the lanes of `rest` (not empty) and returns the one
/// to visit next: sorted by entry distance, farthest stacked first (kSorted), or in lane order with the last
/// lane next. Stacked nodes and leaf data (`leaf_data` + child * `leaf_stride` bytes, when not null) are
/// prefetched.
template <bool kSorted>
[[gnu::always_inline]] inline Bvh8StackEntry stack_entered_children(const Bvh8Node* nodes, const Bvh8Node& n,
                                                                    int k, unsigned rest, const float* t,
                                                                    Bvh8Stack& stack, const char* leaf_data,
                                                                    size_t leaf_stride) {
  Bvh8StackEntry items[8];
  int m = 0;
  for (;;) {
    const Bvh8StackEntry it{n.child[k], n.count[k], t[k]};
    if constexpr (kSorted) {  // insertion sort, farthest first
      int j = m;
      for (; j > 0 && items[j - 1].t < it.t; --j) items[j] = items[j - 1];
      items[j] = it;
    } else {
      items[m] = it;
    }
    ++m;
    if (rest == 0) break;
    k = std::countr_zero(rest);
    rest &= rest - 1;
  }
  for (int j = 0; j + 1 < m; ++j) {
    if (items[j].count == 0) {
      prefetch_node(nodes + items[j].child);
    } else if (leaf_data) {
      prefetch_bytes(leaf_data + items[j].child * leaf_stride, leaf_stride);
    }
    stack.push(items[j]);
  }
  return items[m - 1];
}

/// Front-to-back walk of an 8-wide BVH (not empty). `limit()` is the current upper bound of the box tests
/// (min(tmax, best.t) for closest hit, tmax for any hit); `leaf(first, count)` tests a leaf and returns true
/// to end the walk. Entered children are visited nearest first (kSorted) or in lane order; a stacked child
/// is skipped only when its entry lies strictly beyond limit(). Nodes and leaf data (`leaf_data` + first *
/// `leaf_stride` bytes, when not null) are prefetched as soon as they are known to be entered. Returns true
/// when a leaf ended the walk.
template <bool kCount, bool kSorted, class Limit, class Leaf>
[[gnu::always_inline]] inline bool walk_bvh8(const Bvh8Node* nodes, const Ray& ray, Limit limit, Leaf leaf,
                                             const char* leaf_data, size_t leaf_stride, RayCounters& c) {
  const Bvh8RayTest test(ray);
  Bvh8Stack stack;
  Bvh8StackEntry cur{0, 0, ray.tmin};
  for (;;) {
    if constexpr (kCount) ++c.nodes;
    if (cur.count == 0) {
      const Bvh8Node& n = nodes[cur.child];
      alignas(32) float t[8];
      const unsigned mask = test.entries(n, limit(), t);
      if (mask != 0) {
        const int k = std::countr_zero(mask);
        const unsigned rest = mask & (mask - 1);
        if (rest == 0) {  // one child entered: no stack traffic
          cur = {n.child[k], n.count[k], t[k]};
        } else {
          cur = stack_entered_children<kSorted>(nodes, n, k, rest, t, stack, leaf_data, leaf_stride);
        }
        continue;
      }
    } else {
      if constexpr (kCount) ++c.leaves;
      if (leaf(cur.child, cur.count)) return true;
    }
    if (!stack.pop(limit(), cur)) return false;
  }
}

}  // namespace ab
