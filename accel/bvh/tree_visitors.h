// The binary trees (BVH, sphere tree) and the 8-wide BVH as the one statistics walk
// (accel/common/tree_stats.h) sees them.
#pragma once

#include <cstdint>

#include "accel/bvh/node.h"
#include "accel/bvh/node8.h"
#include "accel/core/aabb.h"

namespace ab {

/// A binary tree in build_bvh's layout (root 0, padding 1, sibling pairs; not empty) over node array Array:
/// nodes by index, the padding node never named, a node's box its member function kBox.
template <class Array, auto kBox>
struct BinaryTreeVisitor {
  using Node = uint32_t;  ///< index in the node array
  const Array& nodes;     ///< the tree

  /// Node 0.
  Node root() const { return 0; }
  /// The node's box.
  AABB box(Node i) const { return (nodes[i].*kBox)(); }
  /// True for a leaf.
  bool is_leaf(Node i) const { return nodes[i].is_leaf(); }
  /// Primitives of a leaf.
  uint32_t count(Node i) const { return nodes[i].count; }
  /// The sibling pair, right first: the walk pops the last child first, so it goes left to right.
  template <class F>
  void children(Node i, F&& f) const {
    f(nodes[i].offset + 1);
    f(nodes[i].offset);
  }
};

/// The binary BVH.
using BvhTreeVisitor = BinaryTreeVisitor<BvhNodeArray, &BvhNode::box>;

/// True when lane k of a wide node holds a child: a leaf (count > 0) or a node (index > 0, as the root is
/// no one's child). Unlike Bvh8Node::used() this does not look at the box, which is empty for a subtree of
/// primitives without bounds (instances of an empty mesh).
template <class WideNode>
bool holds_child(const WideNode& node, int k) {
  return node.count[k] > 0 || node.child[k] != 0;
}

/// An 8-wide tree over node array Array (not empty; lanes with child, count and box(k)): a node is a lane's
/// (child, count) with the lane's box, the root the wide root node with the union of its lanes' boxes (the
/// binary root's box).
template <class Array>
struct WideTreeVisitor {
  using WideNode = typename Array::value_type;  ///< the node type
  /// A wide node (count 0: index child) or a leaf (primitives [child, child + count)), with its box.
  struct Node {
    uint32_t child;  ///< wide node index (count 0) or first primitive (or block) of a leaf
    uint32_t count;  ///< primitives of a leaf, 0 for a wide node
    AABB box;        ///< the lane's box (the union of the root's lanes for the root)
  };
  const Array& nodes;  ///< the tree

  /// The wide root node.
  Node root() const {
    AABB box;
    for (int k = 0; k < WideNode::kWidth; ++k)
      if (holds_child(nodes[0], k)) box.extend(nodes[0].box(k));
    return {0, 0, box};
  }
  /// The node's box.
  AABB box(const Node& n) const { return n.box; }
  /// True for a leaf lane.
  bool is_leaf(const Node& n) const { return n.count > 0; }
  /// Primitives of a leaf.
  uint32_t count(const Node& n) const { return n.count; }
  /// The used lanes of a wide node, last first: the walk pops the last child first, so it goes in lane order.
  template <class F>
  void children(const Node& n, F&& f) const {
    const WideNode& node = nodes[n.child];
    for (int k = WideNode::kWidth - 1; k >= 0; --k)
      if (holds_child(node, k)) f(Node{node.child[k], node.count[k], node.box(k)});
  }
};

/// The 8-wide BVH.
using Bvh8TreeVisitor = WideTreeVisitor<Bvh8NodeArray>;

/// Mean number of children per node of an 8-wide BVH (not empty).
inline double mean_children(const Bvh8NodeArray& nodes) {
  uint64_t lanes = 0;
  for (const Bvh8Node& node : nodes)
    for (int k = 0; k < Bvh8Node::kWidth; ++k) lanes += holds_child(node, k);
  return double(lanes) / double(nodes.size());
}

}  // namespace ab
