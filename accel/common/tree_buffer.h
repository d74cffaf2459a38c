// The flat arrays a tree builder writes (nodes, the leaves' primitive references and an optional payload per
// node, such as the BSP tree's planes) and the one subtree splice of every parallel build: a subtree built
// into a buffer of its own (root at index 0) is moved into its parent's buffer with every index rebased.
// The node type says which of its fields are indices (rebase), so the k-d trees, the octree and the BSP
// tree share this one buffer.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace ab {

/// How far a spliced subtree moves: added to its node, leaf-reference and payload indices.
struct TreeOffsets {
  uint32_t node = 0;     ///< added to every node index (children)
  uint32_t ref = 0;      ///< added to every leaf's first reference
  uint32_t payload = 0;  ///< added to every payload index (the BSP's plane indices)
};

/// Payload of trees whose nodes carry everything themselves.
struct NoNodePayload {};

/// Nodes, leaf references and payload of a tree under construction. Node provides
/// `static Node leaf(uint32_t first, uint32_t count)` and `void rebase(const TreeOffsets&)`.
template <class Node, class Payload = NoNodePayload>
struct TreeBuffer {
  std::vector<Node> nodes;       ///< the nodes, in the order the builder writes them
  std::vector<uint32_t> refs;    ///< the leaves' primitive ids, leaf after leaf
  std::vector<Payload> payload;  ///< per-node data the nodes index (empty for NoNodePayload)

  /// Appends ids to the leaf references and returns the leaf node naming them (the caller places it).
  Node make_leaf(std::span<const uint32_t> ids) {
    const Node leaf = Node::leaf(uint32_t(refs.size()), uint32_t(ids.size()));
    refs.insert(refs.end(), ids.begin(), ids.end());
    return leaf;
  }

  /// Splices in a subtree built into its own buffer (its root at index 0): the root goes to node
  /// `root_slot` (an allocated placeholder, or nodes.size() to append it), the other nodes are appended in
  /// their order, and every index is rebased (a subtree node i > 0 lands at (the first appended index) +
  /// i - 1). Splicing in a fixed order gives the same tree for any thread count.
  void splice(const TreeBuffer& sub, size_t root_slot) {
    if (sub.nodes.empty()) return;
    if (root_slot == nodes.size()) nodes.push_back(sub.nodes[0]);
    const TreeOffsets offsets{uint32_t(nodes.size()) - 1, uint32_t(refs.size()), uint32_t(payload.size())};
    for (size_t i = 0; i < sub.nodes.size(); ++i) {
      Node n = sub.nodes[i];
      n.rebase(offsets);
      if (i == 0) {
        nodes[root_slot] = n;
      } else {
        nodes.push_back(n);
      }
    }
    refs.insert(refs.end(), sub.refs.begin(), sub.refs.end());
    payload.insert(payload.end(), sub.payload.begin(), sub.payload.end());
  }
  /// Appends a subtree after the last node (the k-d and BSP layouts: a subtree's nodes are contiguous).
  void append(const TreeBuffer& sub) { splice(sub, nodes.size()); }
};

}  // namespace ab
