// Refitting a BVH after its primitives moved (Wald, Boulos and Shirley 2007, "Ray tracing deformable scenes
// using dynamic bounding volume hierarchies"): the topology (nodes, leaf order, ids) is kept; every leaf's
// box is recomputed from its primitives' new bounds and its copied triangles (or triangle blocks) refreshed,
// then every interior box is recomputed bottom-up as the union of its children's. A fresh build's node box is
// the same union of the same primitives' bounds (min and max are exact), so a refitted box contains its
// triangles exactly as a built one does and the traversal's widening (box_test.h) keeps hits identical.
//
// As Embree's BVHNRefitter (kernels/bvh/bvh_refit.cpp), the tree is refitted by subtrees in one post-order
// pass: a node's children are refitted first (in parallel for large subtrees, serially below), then its boxes
// are their unions, so every node and leaf block is written once and no node waits on another task. The
// triangles come either from a TrianglePrims (the copy in id order) or straight from the frame's indexed
// Mesh, gathered through the leaf order the build stored (refit(mesh): no copy of the frame is made first).
// The boxes are unions in a fixed order, so the tree is bit for bit the same on any thread count and from
// either source.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <memory>
#include <mutex>
#include <span>
#include <type_traits>
#include <vector>

#include "accel/bvh/leaf_blocks.h"
#include "accel/bvh/node.h"
#include "accel/bvh/node8.h"
#include "accel/core/aabb.h"
#include "accel/core/mesh.h"
#include "accel/core/primitives.h"
#include "accel/core/triangle.h"
#include "accel/core/triangle4.h"

namespace ab {

/// Copies the triangles order[first, first + count) of prims into tris[first, first + count) (leaf order)
/// and returns their bounds.
AABB refresh_leaf_triangles(std::vector<Triangle>& tris, const std::vector<uint32_t>& order, uint32_t first,
                            uint32_t count, const TrianglePrims& prims);
/// The same with the triangles gathered from the indexed mesh (its vertices through its index triples).
AABB refresh_leaf_triangles(std::vector<Triangle>& tris, const std::vector<uint32_t>& order, uint32_t first,
                            uint32_t count, const Mesh& mesh);
/// Repacks the (count + 3) / 4 blocks of the wide leaf from block `first` on from the triangles of their
/// lanes' ids (padding lanes kInvalidId: the zero-area triangle) and returns their bounds.
AABB refresh_leaf_blocks(Bvh8LeafBlocks& leaves, uint32_t first, uint32_t count, const TrianglePrims& prims);
/// The same with the triangles gathered from the indexed mesh.
AABB refresh_leaf_blocks(Bvh8LeafBlocks& leaves, uint32_t first, uint32_t count, const Mesh& mesh);

/// The union of the bounds of primitives ids[0, count) of prims.
template <class P>
AABB leaf_prim_bounds(const P& prims, const uint32_t* ids, uint32_t count) {
  AABB box;
  for (uint32_t k = 0; k < count; ++k) box.extend(prims.bounds(ids[k]));
  return box;
}

/// Subtrees of more than this many nodes are refitted as parallel tasks, smaller ones serially by the task
/// that reaches them: tasks of a few thousand triangles, balanced however uneven the tree. Both arrays are
/// depth-first (the collapse recurses into a child as soon as it allocates it; build_bvh writes each pair's
/// subtrees after it), so a subtree's nodes are the index range from its root to the next sibling's subtree;
/// a wrong layout would only misjudge sizes, never boxes.
inline constexpr uint32_t kRefitTaskNodesWide = 64;
inline constexpr uint32_t kRefitTaskNodesBinary = 1024;

/// The union of the eight lane boxes of a wide node (unused lanes hold the empty box).
AABB wide_node_box(const Bvh8Node& node);

/// Refits the subtree of wide node i, whose nodes are [i, end) (children first): a leaf lane's box is
/// leaf_box(child, count), an interior lane's the union of its node's lanes. Returns the union of node i's
/// lanes.
template <class LeafBox>
AABB refit_wide_subtree(Bvh8NodeArray& wide, uint32_t i, uint32_t end, const LeafBox& leaf_box) {
  Bvh8Node& node = wide[i];
  uint32_t ends[Bvh8Node::kWidth];  // the end of each interior lane's subtree: the next interior lane's node
  for (int k = Bvh8Node::kWidth, next = int(end); k-- > 0;) {
    ends[k] = uint32_t(next);
    if (node.count[k] == 0 && node.child[k] != 0) next = int(node.child[k]);
  }
  const auto lane = [&](int k) {
    if (node.count[k] == 0 && node.child[k] == 0) return;  // an unused lane
    const AABB box = node.count[k] != 0 ? leaf_box(node.child[k], node.count[k])
                                        : refit_wide_subtree(wide, node.child[k], ends[k], leaf_box);
    for (int a = 0; a < 3; ++a) node.bounds[a][k] = box.lo[a], node.bounds[3 + a][k] = box.hi[a];
  };
  if (end - i > kRefitTaskNodesWide)
    tbb::parallel_for(
        tbb::blocked_range<int>(0, Bvh8Node::kWidth, 1),
        [&](const tbb::blocked_range<int>& r) {
          for (int k = r.begin(); k < r.end(); ++k) lane(k);
        },
        tbb::simple_partitioner());
  else
    for (int k = 0; k < Bvh8Node::kWidth; ++k) lane(k);
  return wide_node_box(node);
}

/// Refits the subtree of binary node i, whose nodes are about [i, end) (children first; build_bvh's layout,
/// the children of node i at offset and offset + 1): a leaf's box is leaf_box(offset, count). Returns node
/// i's new box.
template <class LeafBox>
AABB refit_binary_subtree(BvhNodeArray& nodes, uint32_t i, uint32_t end, const LeafBox& leaf_box) {
  BvhNode& n = nodes[i];
  AABB box;
  if (n.is_leaf()) {
    box = leaf_box(n.offset, n.count);
  } else {
    const BvhNode& l = nodes[n.offset];
    const BvhNode& r = nodes[n.offset + 1];
    const uint32_t split = r.is_leaf() ? end : r.offset;  // the left subtree's nodes come first
    const auto left = [&] { refit_binary_subtree(nodes, n.offset, split, leaf_box); };
    const auto right = [&] { refit_binary_subtree(nodes, n.offset + 1, end, leaf_box); };
    if (end - i > kRefitTaskNodesBinary)
      tbb::parallel_invoke(left, right);
    else
      left(), right();
    for (int a = 0; a < 3; ++a)
      box.lo[a] = std::min(l.lo[a], r.lo[a]), box.hi[a] = std::max(l.hi[a], r.hi[a]);
  }
  for (int a = 0; a < 3; ++a) n.lo[a] = box.lo[a], n.hi[a] = box.hi[a];
  return box;
}

/// Refits a binary BVH (leaf boxes from leaf_box(first, count)); returns the root's box (empty: no nodes).
template <class LeafBox>
AABB refit_binary(BvhNodeArray& nodes, const LeafBox& leaf_box) {
  return nodes.empty() ? AABB{} : refit_binary_subtree(nodes, 0, uint32_t(nodes.size()), leaf_box);
}

/// Refits an 8-wide BVH (leaf lane boxes from leaf_box(child, count)); returns the union of the root's
/// lanes (empty: no nodes).
template <class LeafBox>
AABB refit_wide(Bvh8NodeArray& wide, const LeafBox& leaf_box) {
  return wide.empty() ? AABB{} : refit_wide_subtree(wide, 0, uint32_t(wide.size()), leaf_box);
}

/// The refit of a Bvh (bvh.h) over its primitive set's new positions; a friend of Bvh, so the BVH classes
/// carry only the hooks that call it.
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
      {
        const std::lock_guard<std::mutex> lock(b.frame_mutex_);
        b.frame_mesh_.reset();
        b.prims_ = std::move(prims);
      }
      refit_from(b, *b.prims_);
      b.bounds_ = b.prims_->bounds();
      return true;
    }
  }

  /// Refits b (a BVH over triangles) straight from the frame's indexed mesh (same triangle count and ids):
  /// the leaves gather their triangles from it; b's TrianglePrims of the frame is made only when something
  /// asks for it (a rebuild, the quality metrics: Bvh::current_prims). False, with b unchanged, when the
  /// count differs.
  static bool refit_mesh(B& b, std::shared_ptr<const Mesh> mesh) {
    if (!mesh || !b.prims_ || mesh->size() != b.prims_->size()) return false;
    b.bounds_ = refit_from(b, *mesh);
    const std::lock_guard<std::mutex> lock(b.frame_mutex_);
    b.frame_mesh_ = std::move(mesh);
    return true;
  }

 private:
  /// Refits the tree of b from `source` (its primitive set, or a Mesh for triangles); returns the union of
  /// the leaves' boxes.
  template <class S>
  static AABB refit_from(B& b, const S& source) {
    if (b.config_.width == 8) {
      b.binary_.sah_cost = 0.0;  // the binary tree is gone: its SAH cost is not computed after a refit
      return refit_wide(b.wide_, [&](uint32_t first, uint32_t count) {
        if constexpr (B::kCopiesTriangles)
          return refresh_leaf_blocks(b.blocks_, first, count, source);
        else
          return leaf_prim_bounds(source, &b.order_[first], count);
      });
    }
    return refit_binary(b.nodes_, [&](uint32_t first, uint32_t count) {
      if constexpr (B::kCopiesTriangles)
        return refresh_leaf_triangles(b.tris_, b.order_, first, count, source);
      else
        return leaf_prim_bounds(source, &b.order_[first], count);
    });
  }
};

}  // namespace ab
