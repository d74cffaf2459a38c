// The one statistics walk: a depth-first pass over a finished tree that fills BuildStats' node, leaf,
// depth, leaf-size histogram, reference and SAH-cost figures, the same way for every structure. A
// structure describes its tree through a small visitor instead of writing the walk itself:
//
//   struct Visitor {
//     using Node = ...;                                   // a handle: index, flags, box, as the tree needs
//     Node root() const;
//     AABB box(const Node&) const;                        // for the SAH cost (the node's area)
//     bool is_leaf(const Node&) const;
//     uint32_t count(const Node&) const;                  // primitives of a leaf (0 for an empty leaf)
//     template <class F> void children(const Node&, F&& f) const;  // f(child) for every child
//   };
//
// Every node the visitor names counts as a node (interior nodes and leaves, empty leaves that a parent only
// flags included); the root is at depth 0. The SAH cost is SahTreeCost's with unit costs, normalized by the
// root's area, so it compares across structures.
#pragma once

#include <concepts>
#include <cstdint>
#include <utility>
#include <vector>

#include "accel/common/sah.h"
#include "accel/core/stats.h"

namespace ab {

/// What the walk needs of a visitor (see the file comment).
template <class V>
concept TreeVisitor = requires(const V& v, const typename V::Node& n) {
  { v.root() } -> std::convertible_to<typename V::Node>;
  { v.box(n) } -> std::convertible_to<AABB>;
  { v.is_leaf(n) } -> std::convertible_to<bool>;
  { v.count(n) } -> std::convertible_to<uint32_t>;
  v.children(n, [](const typename V::Node&) {});
};

/// Walks the tree `v` describes and adds its figures to `stats` (nodes, leaves, empty leaves, depths,
/// histogram, references, sah_cost). Leaves `stats`' other fields as they are.
template <TreeVisitor V>
void walk_tree_stats(const V& v, BuildStats& stats) {
  using Node = typename V::Node;
  const Node root = v.root();
  // Areas in the root's area frame (sah.h), so the ratios hold at any scale.
  const float frame = area_frame(v.box(root).extent());
  auto area_of = [frame](const AABB& box) { return area_of_extent(box.extent() * frame); };
  SahTreeCost sah(area_of(v.box(root)));
  std::vector<std::pair<Node, uint32_t>> todo{{root, 0u}};
  while (!todo.empty()) {
    const auto [node, depth] = todo.back();
    todo.pop_back();
    ++stats.nodes;
    const float area = area_of(v.box(node));
    if (v.is_leaf(node)) {
      const uint32_t n = v.count(node);
      stats.add_leaf(n, depth);
      sah.add_leaf(area, n);
      continue;
    }
    sah.add_interior(area);
    v.children(node, [&](const Node& child) { todo.push_back({child, depth + 1}); });
  }
  stats.sah_cost = sah.cost();
}

}  // namespace ab
