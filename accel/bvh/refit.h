// Refitting a BVH after its primitives moved (Wald, Boulos and Shirley 2007, "Ray tracing deformable scenes
// using dynamic bounding volume hierarchies"): the topology (nodes, leaf order, ids) is kept; every leaf's
// box is recomputed from its primitives' new bounds and its copied triangles (or triangle blocks) refreshed,
// then every interior box is recomputed bottom-up as the union of its children's. A fresh build's node box is
// the same union of the same primitives' bounds (min and max are exact), so a refitted box contains its
// triangles exactly as a built one does and the traversal's widening (box_test.h) keeps hits identical.
//
// As Embree's BVHNRefitter (kernels/bvh/bvh_refit.cpp), the tree is refitted by subtrees in one post-order
// pass: a serial descent picks subtrees of a bounded size, each is refitted (leaf blocks and boxes together,
// children before their parent) in one task of a parallel loop, then the few nodes above them serially, so
// every node and leaf block is written once and no task waits on another. The triangles come either from a
// TrianglePrims (the copy in id order) or straight from the frame's indexed Mesh, gathered through the leaf
// order the build stored (refit(mesh): no copy of the frame is made first). The boxes are unions in a fixed
// order, so the tree is bit for bit the same on any thread count and from either source.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

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

/// The refit is split as Embree's BVHNRefitter splits it: a serial descent from the root collects the
/// subtrees of at most `limit` nodes whose parents are larger (in depth-first order), a parallel loop refits
/// each of them serially in one task (no task waits on another, no atomics), and a serial pass refits the few
/// nodes above them, taking the subtrees' boxes in the same order. limit is the tree's size over
/// kRefitTasksPerThread x threads, at least the tree's minimum below (smaller trees are refitted serially):
/// on two threads the 1M sphereflake's 60918 wide nodes give subtrees of at most 951 nodes, about 260 of
/// them, which TBB's stealing balances however uneven they are. Both arrays are depth-first (the collapse
/// recurses into a child as soon as it allocates it; build_bvh writes each pair's subtrees after it), so a
/// subtree's nodes are the index range from its root to the next sibling's subtree; a wrong layout would
/// only misjudge sizes, never boxes.
inline constexpr uint32_t kRefitTasksPerThread = 32;
inline constexpr uint32_t kRefitTaskNodesWide = 64;
inline constexpr uint32_t kRefitTaskNodesBinary = 1024;

/// The union of the eight lane boxes of a wide node (unused lanes hold the empty box).
AABB wide_node_box(const Bvh8Node& node);

/// What refit_tree reads of either tree: its depth-first node array, the function giving a leaf's box and
/// the size below which the whole tree is refitted serially.
template <class Nodes, class LeafBox, uint32_t kMin>
struct RefitTreeBase {
  Nodes& nodes;             ///< the node array (children after their parent)
  const LeafBox& leaf_box;  ///< leaf_box(first, count): a leaf's box, its triangles or blocks refreshed
  static constexpr uint32_t kMinTaskNodes = kMin;  ///< smaller trees are refitted serially
  /// The number of nodes.
  uint32_t size() const { return uint32_t(nodes.size()); }
};

/// A wide tree as refit_tree sees it: node i (whose subtree is [i, end)) refits its lanes, a leaf lane's box
/// leaf_box(child, count), an interior lane's child_box(child, child_end), in lane order.
template <class LeafBox>
struct WideRefitTree : RefitTreeBase<Bvh8NodeArray, LeafBox, kRefitTaskNodesWide> {
  /// Calls f(child, child_end) for each interior lane of node i, in lane order.
  template <class F>
  void for_each_child(uint32_t i, uint32_t end, F&& f) const {
    const Bvh8Node& node = this->nodes[i];
    uint32_t ends[Bvh8Node::kWidth];
    lane_ends(node, end, ends);
    for (int k = 0; k < Bvh8Node::kWidth; ++k)
      if (node.count[k] == 0 && node.child[k] != 0) f(node.child[k], ends[k]);
  }
  /// Writes node i's lane boxes (interior lanes from child_box) and returns their union.
  template <class ChildBox>
  AABB refit_node(uint32_t i, uint32_t end, const ChildBox& child_box) const {
    Bvh8Node& node = this->nodes[i];
    uint32_t ends[Bvh8Node::kWidth];
    lane_ends(node, end, ends);
    for (int k = 0; k < Bvh8Node::kWidth; ++k) {
      if (node.count[k] == 0 && node.child[k] == 0) continue;  // an unused lane
      const AABB box = node.count[k] != 0 ? this->leaf_box(node.child[k], node.count[k])
                                          : child_box(node.child[k], ends[k]);
      for (int a = 0; a < 3; ++a) node.bounds[a][k] = box.lo[a], node.bounds[3 + a][k] = box.hi[a];
    }
    return wide_node_box(node);
  }

 private:
  /// The end of each interior lane's subtree: the next interior lane's node (the last one's: end).
  static void lane_ends(const Bvh8Node& node, uint32_t end, uint32_t* ends) {
    for (int k = Bvh8Node::kWidth, next = int(end); k-- > 0;) {
      ends[k] = uint32_t(next);
      if (node.count[k] == 0 && node.child[k] != 0) next = int(node.child[k]);
    }
  }
};

/// A binary tree as refit_tree sees it (build_bvh's layout: the children of node i at offset and offset + 1,
/// its subtree about [i, end)); a leaf's box is leaf_box(offset, count).
template <class LeafBox>
struct BinaryRefitTree : RefitTreeBase<BvhNodeArray, LeafBox, kRefitTaskNodesBinary> {
  /// Calls f(child, child_end) for the two children of node i (none for a leaf), left first.
  template <class F>
  void for_each_child(uint32_t i, uint32_t end, F&& f) const {
    const BvhNode& n = this->nodes[i];
    if (n.is_leaf()) return;
    const BvhNode& r = this->nodes[n.offset + 1];
    f(n.offset, r.is_leaf() ? end : r.offset);  // the left subtree's nodes come first
    f(n.offset + 1, end);
  }
  /// Writes node i's box (an interior node's from child_box of its children) and returns it.
  template <class ChildBox>
  AABB refit_node(uint32_t i, uint32_t end, const ChildBox& child_box) const {
    BvhNode& n = this->nodes[i];
    AABB box;
    if (n.is_leaf()) {
      box = this->leaf_box(n.offset, n.count);
    } else {
      AABB child[2];
      int k = 0;
      for_each_child(i, end, [&](uint32_t c, uint32_t e) { child[k++] = child_box(c, e); });
      for (int a = 0; a < 3; ++a)
        box.lo[a] = std::min(child[0].lo[a], child[1].lo[a]),
        box.hi[a] = std::max(child[0].hi[a], child[1].hi[a]);
    }
    for (int a = 0; a < 3; ++a) n.lo[a] = box.lo[a], n.hi[a] = box.hi[a];
    return box;
  }
};

/// Refits the subtree [i, end) of tree in one task, children before their parent; returns node i's box.
template <class Tree>
AABB refit_subtree_serially(const Tree& tree, uint32_t i, uint32_t end) {
  return tree.refit_node(i, end, [&](uint32_t c, uint32_t e) { return refit_subtree_serially(tree, c, e); });
}

/// Refits a whole tree (WideRefitTree or BinaryRefitTree) by subtrees as described above; returns the root's
/// box (empty: no nodes). The boxes are the serial refit's bits on any thread count.
template <class Tree>
AABB refit_tree(const Tree& tree) {
  const uint32_t size = tree.size();
  if (size == 0) return AABB{};
  const uint32_t threads = uint32_t(std::max(1, tbb::this_task_arena::max_concurrency()));
  const uint32_t limit = std::max(Tree::kMinTaskNodes, size / (kRefitTasksPerThread * threads));
  if (size <= limit || threads == 1) return refit_subtree_serially(tree, 0, size);
  std::vector<std::pair<uint32_t, uint32_t>> tasks;  // the subtrees [first, second), depth-first
  const auto collect = [&](const auto& self, uint32_t i, uint32_t end) -> void {
    if (end - i <= limit) {
      tasks.emplace_back(i, end);
      return;
    }
    tree.for_each_child(i, end, [&](uint32_t c, uint32_t e) { self(self, c, e); });
  };
  collect(collect, 0, size);
  std::vector<AABB> boxes(tasks.size());
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, tasks.size(), 1),
      [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t < r.end(); ++t)
          boxes[t] = refit_subtree_serially(tree, tasks[t].first, tasks[t].second);
      },
      tbb::simple_partitioner());
  size_t next = 0;  // the top pass meets the subtrees in the order collect found them
  const auto top = [&](const auto& self, uint32_t i, uint32_t end) -> AABB {
    return tree.refit_node(
        i, end, [&](uint32_t c, uint32_t e) { return e - c <= limit ? boxes[next++] : self(self, c, e); });
  };
  return top(top, 0, size);
}

/// Refits a binary BVH (leaf boxes from leaf_box(first, count)); returns the root's box (empty: no nodes).
template <class LeafBox>
AABB refit_binary(BvhNodeArray& nodes, const LeafBox& leaf_box) {
  return refit_tree(BinaryRefitTree<LeafBox>{{nodes, leaf_box}});
}

/// Refits an 8-wide BVH (leaf lane boxes from leaf_box(child, count)); returns the union of the root's
/// lanes (empty: no nodes).
template <class LeafBox>
AABB refit_wide(Bvh8NodeArray& wide, const LeafBox& leaf_box) {
  return refit_tree(WideRefitTree<LeafBox>{{wide, leaf_box}});
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
