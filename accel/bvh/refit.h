// Refitting a BVH after its primitives moved (Wald, Boulos and Shirley 2007, "Ray tracing deformable scenes
// using dynamic bounding volume hierarchies"): the topology (nodes, leaf order, ids) is kept; every leaf's
// box is recomputed from its primitives' new bounds and its copied triangles (or triangle blocks) refreshed,
// then every interior box is recomputed bottom-up as the union of its children's. A fresh build's node box is
// the same union of the same primitives' bounds (min and max are exact), so a refitted box contains its
// triangles exactly as a built one does and the traversal's widening (box_test.h) keeps hits identical.
//
// The binary and the wide arrays both store every child after its parent (depth-first pairs; the collapse
// appends wide children), so one reverse pass over the array is bottom-up. Leaves are refitted in parallel;
// the interior pass is serial (a few percent of the leaves' work).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <memory>
#include <span>
#include <type_traits>
#include <vector>

#include "accel/bvh/leaf_blocks.h"
#include "accel/bvh/node.h"
#include "accel/bvh/node8.h"
#include "accel/core/aabb.h"
#include "accel/core/primitives.h"
#include "accel/core/triangle.h"
#include "accel/core/triangle4.h"

namespace ab {

/// Recomputes every interior box of a binary BVH (build_bvh's layout) from its children, bottom-up; leaf
/// boxes must already be current.
void refit_binary_interiors(BvhNodeArray& nodes);
/// Recomputes every interior lane box of an 8-wide BVH from the lanes of the node it points to, bottom-up;
/// leaf lane boxes must already be current.
void refit_wide_interiors(Bvh8NodeArray& wide);
/// Copies the `count` triangles `ids` of prims into `out` (leaf order) and returns their bounds.
AABB refresh_leaf_triangles(Triangle* out, const uint32_t* ids, uint32_t count, const TrianglePrims& prims);
/// Repacks the (count + 3) / 4 blocks of a wide leaf from the triangles `ids` (four lanes per block, padding
/// lanes kInvalidId) and returns their bounds.
AABB refresh_leaf_blocks(Triangle4* blocks, const uint32_t* ids, uint32_t count, const TrianglePrims& prims);

/// The union of the bounds of primitives ids[0, count) of prims.
template <class P>
AABB leaf_prim_bounds(const P& prims, const uint32_t* ids, uint32_t count) {
  AABB box;
  for (uint32_t k = 0; k < count; ++k) box.extend(prims.bounds(ids[k]));
  return box;
}

/// Sets every leaf box of a binary BVH to leaf_box(first, count) (in parallel), then the interiors.
template <class LeafBox>
void refit_binary(BvhNodeArray& nodes, LeafBox&& leaf_box) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nodes.size(), 1024),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        BvhNode& n = nodes[i];
                        if (i == 1 || !n.is_leaf()) continue;  // node 1 is padding
                        const AABB box = leaf_box(n.offset, n.count);
                        for (int a = 0; a < 3; ++a) n.lo[a] = box.lo[a], n.hi[a] = box.hi[a];
                      }
                    });
  refit_binary_interiors(nodes);
}

/// Sets every leaf lane box of an 8-wide BVH to leaf_box(child, count) (in parallel), then the interiors.
template <class LeafBox>
void refit_wide(Bvh8NodeArray& wide, LeafBox&& leaf_box) {
  tbb::parallel_for(tbb::blocked_range<size_t>(0, wide.size(), 256),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        Bvh8Node& node = wide[i];
                        for (int k = 0; k < Bvh8Node::kWidth; ++k) {
                          if (node.count[k] == 0) continue;
                          const AABB box = leaf_box(node.child[k], node.count[k]);
                          for (int a = 0; a < 3; ++a)
                            node.bounds[a][k] = box.lo[a], node.bounds[3 + a][k] = box.hi[a];
                        }
                      }
                    });
  refit_wide_interiors(wide);
}

/// The refit of a Bvh (bvh.h) over its primitive set's new positions; a friend of Bvh, so the BVH classes
/// carry only the hook that calls it.
template <class B>
struct BvhRefit {
  /// Refits b over `prims` (same primitive count and ids). False, with b unchanged, when Q is not b's
  /// primitive set or the count differs.
  template <class Q>
  static bool refit(B& b, std::shared_ptr<const Q> prims) {
    if constexpr (!std::is_same_v<Q, typename B::Prims>) {
      return false;
    } else {
      if (!prims || !b.prims_ || prims->size() != b.prims_->size()) return false;
      b.prims_ = std::move(prims);
      const auto& p = *b.prims_;
      if (b.config_.width == 8) {
        refit_wide_tree(b, p);
        b.binary_.sah_cost = 0.0;  // the binary tree is gone: its SAH cost is not computed after a refit
      } else if (!b.nodes_.empty()) {
        refit_binary(b.nodes_, [&](uint32_t first, uint32_t count) {
          if constexpr (B::kCopiesTriangles)
            return refresh_leaf_triangles(&b.tris_[first], &b.order_[first], count, p);
          else
            return leaf_prim_bounds(p, &b.order_[first], count);
        });
      }
      return true;
    }
  }

 private:
  /// The wide tree: triangle blocks repacked (lane j of leaf block child + j / 4 is ids[4 child + j]) or
  /// other primitives' bounds through the leaf order.
  template <class P>
  static void refit_wide_tree(B& b, const P& p) {
    if (b.wide_.empty()) return;
    refit_wide(b.wide_, [&](uint32_t first, uint32_t count) {
      if constexpr (B::kCopiesTriangles)
        return refresh_leaf_blocks(&b.blocks_.blocks[first], &b.blocks_.ids[4 * size_t(first)], count, p);
      else
        return leaf_prim_bounds(p, &b.order_[first], count);
    });
  }
};

}  // namespace ab
