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
/// the returned mask is set when the ray enters that box. The general path is BvhPairTest::entry's
/// arithmetic lane by lane: (plane - org) * inv_dir with planes chosen by the direction's sign, reductions
/// that keep the bound on NaN, widen_near / widen_far, then the clip. For tmin >= 0 (every ray but a few)
/// the widening is folded into the reciprocals, as Embree's robust traversal folds its ulp margin into
/// rdir_near / rdir_far (kernels/bvh/node_intersector1.h; Ize 2013, "Robust BVH ray traversal"): an entry
/// clipped to tmin >= 0 needs only near distances shrunk toward zero when positive (a negative one is
/// clipped anyway) and far distances grown when positive (a negative one is a miss either way), so
/// (plane - org) * (inv_dir * (1 -+ kBoxEps)) is as conservative as widening after the product, to within
/// an ulp of a margin 256 ulps wide. That takes the widening's compares, blends and multiplies out of every
/// node (20 operations instead of 27).
struct Bvh8RayTest {
  /// Prepares the per-ray data of the box tests (broadcast to eight lanes with AVX2).
  explicit Bvh8RayTest(const Ray& ray) : rd(ray), tmin(ray.tmin), folded(ray.tmin >= 0.0f) {
    for (int a = 0; a < 3; ++a) {
      near_row[a] = a + 3 * rd.neg[a];
      far_row[a] = a + 3 * (1 - rd.neg[a]);
    }
#if defined(__AVX2__)
    for (int a = 0; a < 3; ++a) {
      org[a] = _mm256_set1_ps(rd.org[a]);
      inv[a] = _mm256_set1_ps(rd.inv_dir[a]);
      inv_near[a] = _mm256_set1_ps(rd.inv_dir[a] * (1.0f - kBoxEps));
      inv_far[a] = _mm256_set1_ps(rd.inv_dir[a] * (1.0f + kBoxEps));
    }
    tmin8 = _mm256_set1_ps(tmin);
#endif
  }

  /// Entry distances into t[0..7]; returns the mask of lanes entered.
  [[gnu::always_inline]] unsigned entries(const Bvh8Node& n, float limit, float* t) const {
#if defined(__AVX2__)
    return entries_of_rows([&](int row) { return _mm256_load_ps(n.bounds[row]); }, limit, t);
#else
    return entries_scalar(n, limit, t);
#endif
  }

#if defined(__AVX2__)
  /// The same for boxes given as rows (`n(row)`: eight lanes of bounds row lo x, y, z, hi x, y, z), such as
  /// boxes a motion node interpolates at the ray's time (motion_node8.h).
  template <class Rows>
  [[gnu::always_inline]] unsigned entries_of_rows(const Rows& n, float limit, float* t) const {
    const __m256 t0 = folded ? folded_near(n) : general_near(n);
    const __m256 t1 = folded ? folded_far(n, limit) : general_far(n, limit);
    _mm256_store_ps(t, t0);
    return unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t0, t1, _CMP_LE_OQ)));
  }
  /// (plane - org) * reciprocal on axis a of bounds row `row` (eight lanes).
  template <class Rows>
  [[gnu::always_inline]] static __m256 slab(const Rows& n, int row, __m256 o, __m256 r) {
    return _mm256_mul_ps(_mm256_sub_ps(n(row), o), r);
  }
  /// Folded path: max(near_x, near_y, near_z, tmin), each max keeping the bound on NaN.
  template <class Rows>
  [[gnu::always_inline]] __m256 folded_near(const Rows& n) const {
    __m256 t0 = _mm256_max_ps(slab(n, near_row[2], org[2], inv_near[2]), tmin8);
    t0 = _mm256_max_ps(slab(n, near_row[1], org[1], inv_near[1]), t0);
    return _mm256_max_ps(slab(n, near_row[0], org[0], inv_near[0]), t0);
  }
  /// Folded path: min(far_x, far_y, far_z, limit), each min keeping the bound on NaN.
  template <class Rows>
  [[gnu::always_inline]] __m256 folded_far(const Rows& n, float limit) const {
    __m256 t1 = _mm256_min_ps(slab(n, far_row[2], org[2], inv_far[2]), _mm256_set1_ps(limit));
    t1 = _mm256_min_ps(slab(n, far_row[1], org[1], inv_far[1]), t1);
    return _mm256_min_ps(slab(n, far_row[0], org[0], inv_far[0]), t1);
  }
  /// General path (any tmin): the widened near distance clipped to tmin.
  template <class Rows>
  [[gnu::always_inline]] __m256 general_near(const Rows& n) const {
    __m256 tn = _mm256_set1_ps(-kInf);
    for (int a = 0; a < 3; ++a) tn = _mm256_max_ps(slab(n, near_row[a], org[a], inv[a]), tn);
    const __m256 shrink = _mm256_set1_ps(1.0f - kBoxEps), grow = _mm256_set1_ps(1.0f + kBoxEps);
    tn =
        _mm256_mul_ps(tn, _mm256_blendv_ps(grow, shrink, _mm256_cmp_ps(tn, _mm256_setzero_ps(), _CMP_GT_OQ)));
    return _mm256_max_ps(tn, tmin8);
  }
  /// General path: the widened far distance clipped to limit.
  template <class Rows>
  [[gnu::always_inline]] __m256 general_far(const Rows& n, float limit) const {
    __m256 tf = _mm256_set1_ps(kInf);
    for (int a = 0; a < 3; ++a) tf = _mm256_min_ps(slab(n, far_row[a], org[a], inv[a]), tf);
    const __m256 shrink = _mm256_set1_ps(1.0f - kBoxEps), grow = _mm256_set1_ps(1.0f + kBoxEps);
    tf =
        _mm256_mul_ps(tf, _mm256_blendv_ps(shrink, grow, _mm256_cmp_ps(tf, _mm256_setzero_ps(), _CMP_GT_OQ)));
    return _mm256_min_ps(tf, _mm256_set1_ps(limit));
  }
#endif

  /// The same computation one lane at a time (the portable path, and the reference in tests): the folded
  /// path for tmin >= 0, the general one otherwise.
  unsigned entries_scalar(const Bvh8Node& n, float limit, float* t) const {
    unsigned mask = 0;
    for (int k = 0; k < Bvh8Node::kWidth; ++k) {
      float t0, t1;
      if (folded) {
        t0 = tmin, t1 = limit;
        for (int a = 2; a >= 0; --a) {
          const float near_t = (n.bounds[near_row[a]][k] - rd.org[a]) * (rd.inv_dir[a] * (1.0f - kBoxEps));
          const float far_t = (n.bounds[far_row[a]][k] - rd.org[a]) * (rd.inv_dir[a] * (1.0f + kBoxEps));
          t0 = near_t > t0 ? near_t : t0;
          t1 = far_t < t1 ? far_t : t1;
        }
      } else {
        float tn = -kInf, tf = kInf;
        for (int a = 0; a < 3; ++a) {
          const float near_t = (n.bounds[near_row[a]][k] - rd.org[a]) * rd.inv_dir[a];
          const float far_t = (n.bounds[far_row[a]][k] - rd.org[a]) * rd.inv_dir[a];
          tn = near_t > tn ? near_t : tn;
          tf = far_t < tf ? far_t : tf;
        }
        const float wn = widen_near(tn), wf = widen_far(tf);
        t0 = wn > tmin ? wn : tmin;
        t1 = wf < limit ? wf : limit;
      }
      t[k] = t0;
      if (t0 <= t1) mask |= 1u << k;
    }
    return mask;
  }

  RayBoxData rd;                ///< origin, reciprocal direction, sign bits
  float tmin;                   ///< the ray's tmin (lower clip of every entry)
  bool folded;                  ///< tmin >= 0: the widening is folded into inv_near and inv_far
  int near_row[3], far_row[3];  ///< bounds row of the near and far plane per axis
#if defined(__AVX2__)
  __m256 org[3], inv[3], tmin8;    ///< origin, reciprocal direction and tmin in every lane
  __m256 inv_near[3], inv_far[3];  ///< reciprocals times 1 - kBoxEps and 1 + kBoxEps (folded path)
#endif
};

/// Asks for the cache lines of `bytes` bytes at p ahead of their use (the walk is bound by memory).
[[gnu::always_inline]] inline void prefetch_bytes(const char* p, size_t bytes) {
  for (size_t line = 0; line < bytes; line += 64) __builtin_prefetch(p + line);
}
/// Prefetches a whole node (four lines for Bvh8Node).
template <class Node>
[[gnu::always_inline]] inline void prefetch_node(const Node* n) {
  prefetch_bytes(reinterpret_cast<const char*>(n), sizeof(Node));
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

/// Prefetches what entry e refers to: a node, or its leaf's data when leaf_data is not null.
template <class Node>
[[gnu::always_inline]] inline void prefetch_entry(const Node* nodes, const Bvh8StackEntry& e,
                                                  const char* leaf_data, size_t leaf_stride) {
  if (e.count == 0) {
    prefetch_node(nodes + e.child);
  } else if (leaf_data) {
    prefetch_bytes(leaf_data + e.child * leaf_stride, leaf_stride);
  }
}

/// Places the entered lanes of n (mask, at least two) in items[] nearest last, without branches: as in
/// Embree 3's traverser (kernels/bvh/bvh_traverser1.h), each lane's key is its entry distance's bits with
/// the lane index in the three low bits (unique keys; the order of non-negative floats is that of their bits
/// as integers), and a lane's place is the number of entered lanes whose key is greater, found with one
/// eight-lane compare. Distances that tie or are negative (tmin < 0) may come in another order; any order
/// gives the same hits. Returns the number of lanes placed.
template <class Node>
[[gnu::always_inline]] inline int rank_entered_children(const Node& n, unsigned mask, const float* t,
                                                        Bvh8StackEntry* items) {
#if defined(__AVX2__)
  const __m256i keys = _mm256_or_si256(
      _mm256_and_si256(_mm256_load_si256(reinterpret_cast<const __m256i*>(t)), _mm256_set1_epi32(~7)),
      _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  alignas(32) int32_t key[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(key), keys);
  for (unsigned rest = mask; rest; rest &= rest - 1) {
    const int k = std::countr_zero(rest);
    const unsigned farther = unsigned(
        _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(keys, _mm256_set1_epi32(key[k])))));
    items[std::popcount(farther & mask)] = {n.child[k], n.count[k], t[k]};
  }
  return std::popcount(mask);
#else
  int m = 0;
  for (unsigned rest = mask; rest; rest &= rest - 1) {  // insertion sort, farthest first
    const int k = std::countr_zero(rest);
    int j = m++;
    for (; j > 0 && items[j - 1].t < t[k]; --j) items[j] = items[j - 1];
    items[j] = {n.child[k], n.count[k], t[k]};
  }
  return m;
#endif
}

/// Stacks the children of node n entered by the lanes of mask (at least two) and returns the one to visit
/// next: sorted by entry distance, farthest stacked first (kSorted), or in lane order with the last lane
/// next. Two children (the most frequent case after one) take one compare and one push, as in Embree 3's
/// traverser (kernels/bvh/bvh_traverser1.h); more are ranked by rank_entered_children. Stacked nodes and
/// leaf data (`leaf_data` + child * `leaf_stride` bytes, when not null) are prefetched.
template <bool kSorted, class Node>
[[gnu::always_inline]] inline Bvh8StackEntry stack_entered_children(const Node* nodes, const Node& n,
                                                                    unsigned mask, const float* t,
                                                                    Bvh8Stack& stack, const char* leaf_data,
                                                                    size_t leaf_stride) {
  const unsigned rest = mask & (mask - 1);
  if ((rest & (rest - 1)) == 0) {
    const int k0 = std::countr_zero(mask), k1 = std::countr_zero(rest);
    int next = k1, later = k0;  // lane order: the last lane next
    if constexpr (kSorted) {
      if (t[k0] <= t[k1]) next = k0, later = k1;  // the nearer one next
    }
    const Bvh8StackEntry stacked{n.child[later], n.count[later], t[later]};
    prefetch_entry(nodes, stacked, leaf_data, leaf_stride);
    stack.push(stacked);
    return {n.child[next], n.count[next], t[next]};
  }
  Bvh8StackEntry items[8];
  int m = 0;
  if constexpr (kSorted) {
    m = rank_entered_children(n, mask, t, items);
  } else {
    for (unsigned left = mask; left; left &= left - 1) {
      const int k = std::countr_zero(left);
      items[m++] = {n.child[k], n.count[k], t[k]};
    }
  }
  for (int j = 0; j + 1 < m; ++j) {
    prefetch_entry(nodes, items[j], leaf_data, leaf_stride);
    stack.push(items[j]);
  }
  return items[m - 1];
}

/// Front-to-back walk of an 8-wide BVH (not empty; Bvh8Node, or a node of another bound with child[8],
/// count[8] and the test it names, `using RayTest = ...;` with entries(node, limit, t)). `limit()` is the
/// current upper bound of the box tests (min(tmax, best.t) for closest hit, tmax for any hit); `leaf(first,
/// count)` tests a leaf and returns true to end the walk. Entered children are visited nearest first
/// (kSorted) or in lane order; a stacked child is skipped only when its entry lies strictly beyond limit().
/// Nodes and leaf data (`leaf_data` + first * `leaf_stride` bytes, when not null) are prefetched as soon as
/// they are known to be entered. Returns true when a leaf ended the walk.
/// `test` is the ray's box test (Node::RayTest made from ray), made by the caller so that it may share its
/// RayBoxData with the leaves' test (Ray4): the reciprocals are then divided once per ray.
template <bool kCount, bool kSorted, class Limit, class Leaf, class Node>
[[gnu::always_inline]] inline bool walk_bvh8(const Node* nodes, const typename Node::RayTest& test,
                                             const Ray& ray, Limit limit, Leaf leaf, const char* leaf_data,
                                             size_t leaf_stride, RayCounters& c) {
  Bvh8Stack stack;
  Bvh8StackEntry cur{0, 0, ray.tmin};
  for (;;) {
    if constexpr (kCount) ++c.nodes;
    if (cur.count == 0) {
      const Node& n = nodes[cur.child];
      alignas(32) float t[8];
      const unsigned mask = test.entries(n, limit(), t);
      if (mask != 0) {
        if ((mask & (mask - 1)) == 0) {  // one child entered: no stack traffic
          const int k = std::countr_zero(mask);
          cur = {n.child[k], n.count[k], t[k]};
        } else {
          cur = stack_entered_children<kSorted>(nodes, n, mask, t, stack, leaf_data, leaf_stride);
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

/// walk_bvh8 with the box test made here.
template <bool kCount, bool kSorted, class Limit, class Leaf, class Node>
[[gnu::always_inline]] inline bool walk_bvh8(const Node* nodes, const Ray& ray, Limit limit, Leaf leaf,
                                             const char* leaf_data, size_t leaf_stride, RayCounters& c) {
  const typename Node::RayTest test(ray);
  return walk_bvh8<kCount, kSorted>(nodes, test, ray, limit, leaf, leaf_data, leaf_stride, c);
}

}  // namespace ab
