// The one walk of the binary BVH, for closest hit and any hit alike: depth-first with an explicit stack,
// nearer child first, both child boxes of a sibling pair tested at once.
#pragma once

#include <algorithm>
#include <cstdint>

#include "accel/bvh/node.h"
#include "accel/common/traversal_stack.h"
#include "accel/core/box_test.h"
#include "accel/core/ray.h"
#include "accel/core/stats.h"

namespace ab {

/// Entry distances of a ray into the two nodes of a sibling pair (+inf for a miss), clipped to
/// [tmin, limit]. The arithmetic is slab_test's: per-axis distances (plane - org) * inv_dir with the planes
/// chosen by the direction's sign, NaN ignored; the widening is applied once to the reduced near and far
/// distance, which equals widening every axis first because widening is monotonic. (A 256-bit version
/// testing both boxes at once measured slower on this machine than this scalar one.)
struct BvhPairTest {
  /// Prepares the per-ray data of the box tests.
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

  RayBoxData rd;                    ///< origin, reciprocal direction, sign bits
  float tmin;                       ///< the ray's tmin (lower clip of every entry)
  int near_index[3], far_index[3];  ///< float index in a node of the near and far plane per axis
};

/// The test of a binary node type's sibling pairs: BvhPairTest for the box nodes; a node of another bound
/// names its own (`using PairTest = ...;`, as bvh-sphere's SphereNode does).
template <class Node>
struct BvhPairTestOf {
  using type = typename Node::PairTest;  ///< the node's own test
};
/// The box nodes' test.
template <>
struct BvhPairTestOf<BvhNode> {
  using type = BvhPairTest;  ///< the slab test of both boxes
};

/// A node waiting on the binary walk's stack, with the distance at which the ray enters it.
struct BvhStackEntry {
  uint32_t node;  ///< index in the node array
  float t;        ///< entry distance

  /// The entry distance (what TraversalStack prunes by).
  float entry() const { return t; }
};

/// Front-to-back walk of a binary BVH (nodes as build_bvh lays them out; not empty; BvhNode, or a node of
/// another bound with is_leaf(), offset and count, tested by its BvhPairTestOf). `limit()` is the
/// current upper bound of the box tests (min(tmax, best.t) for closest hit, tmax for any hit);
/// `leaf(first, count)` tests a leaf's primitives [first, first + count) of leaf order and returns true
/// to end the walk. The nearer entered child is visited first, the farther one is stacked (and, with
/// kPrefetchFar, its children's pair prefetched: closest hit visits most stacked nodes, any hit often ends
/// before); a stacked node is skipped only when its entry lies strictly beyond limit(). Returns true when
/// a leaf ended the walk.
template <bool kCount, bool kPrefetchFar, class Limit, class Leaf, class Node>
[[gnu::always_inline]] inline bool walk_bvh2(const Node* nodes, const Ray& ray, Limit limit, Leaf leaf,
                                             RayCounters& c) {
  const typename BvhPairTestOf<Node>::type test(ray);
  if (test.entry(nodes[0], limit()) == kInf) return false;
  TraversalStack<BvhStackEntry, kBvhMaxDepth + 2> stack;
  uint32_t idx = 0;
  for (;;) {
    const Node& n = nodes[idx];
    if constexpr (kCount) ++c.nodes;
    if (!n.is_leaf()) {
      const uint32_t l = n.offset, r = n.offset + 1;
      float tl, tr;
      test.entries(nodes + l, limit(), tl, tr);
      if (tl != kInf && tr != kInf) {
        const bool left_first = tl <= tr;
        idx = left_first ? l : r;
        const uint32_t far = left_first ? r : l;
        stack.push({far, left_first ? tr : tl});
        if constexpr (kPrefetchFar)
          if (!nodes[far].is_leaf()) __builtin_prefetch(nodes + nodes[far].offset);
        continue;
      }
      if (tl != kInf || tr != kInf) {
        idx = tl != kInf ? l : r;
        continue;
      }
    } else {
      if constexpr (kCount) ++c.leaves;
      if (leaf(n.offset, n.count)) return true;
    }
    BvhStackEntry next;
    if (!stack.pop(limit(), next)) return false;
    idx = next.node;
  }
}

}  // namespace ab
