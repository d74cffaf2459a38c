// End-point overlap (EPO), the BVH quality metric of Aila, Karras and Laine 2013 ("On quality metrics of
// bounding volume hierarchies", HPG 2013, section 4). A ray that ends on the surface S visits every node
// whose box contains its end point; the nodes visited although the end point is not in their subtree are
// the overhead the SAH does not see (it prices only the boxes' areas, not what they overlap). EPO sums
// that overhead over all nodes n:
//
//   EPO = sum_n C(n) A(Z_n) / A(S),  Z_n = the part of the surfaces of triangles outside n's subtree
//                                          that lies inside n's box,
//
// with C(n) the node's cost as the SAH prices it: traversal for an interior node, intersection x its
// triangles for a leaf (unit costs, as BuildStats::sah_cost, so the two compare across structures).
// A(Z_n) is computed exactly: each triangle is clipped (Sutherland and Hodgman 1974, accel/core/clip.h) to
// the boxes of the nodes it overlaps, found by walking the tree from the root; a child's box lies in its
// parent's in a BVH, so a triangle that misses a box misses its whole subtree.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "accel/common/tree_stats.h"
#include "accel/core/clip.h"
#include "accel/core/triangle.h"

namespace ab {

/// A tree flattened in depth-first preorder, so the subtree of node i is the index range [i, end[i]).
struct EpoTree {
  std::vector<AABB> box;              ///< the node's box
  std::vector<uint32_t> end;          ///< one past the last node of the subtree
  std::vector<float> cost;            ///< C(n): traversal 1 for an interior node, its count for a leaf
  std::vector<uint32_t> child_begin;  ///< children of node i: child_list[child_begin[i] .. [i + 1])
  std::vector<uint32_t> child_list;   ///< child indices, grouped by parent
  std::vector<uint32_t> leaf_begin;   ///< leaves holding primitive p: leaf_list[leaf_begin[p] .. [p + 1])
  std::vector<uint32_t> leaf_list;    ///< leaf indices, grouped by primitive
};

/// Area of a convex polygon (in double, from a fan around its first vertex).
inline double polygon_area(const ClipPolygon& poly) {
  glm::dvec3 sum(0.0);
  const glm::dvec3 o(poly.v[0]);
  for (int i = 1; i + 1 < poly.n; ++i)
    sum += glm::cross(glm::dvec3(poly.v[i]) - o, glm::dvec3(poly.v[i + 1]) - o);
  return 0.5 * glm::length(sum);
}

/// The triangle as a polygon.
inline ClipPolygon triangle_polygon(const Triangle& t) {
  ClipPolygon poly;
  poly.v[0] = t.v0;
  poly.v[1] = t.v1;
  poly.v[2] = t.v2;
  poly.n = 3;
  return poly;
}

/// Groups (key, value) pairs by key into begin offsets (keys < n) and a value list, values in input order.
void group_by_key(const std::vector<std::pair<uint32_t, uint32_t>>& pairs, size_t n,
                  std::vector<uint32_t>& begin, std::vector<uint32_t>& list);

/// Flattens the tree `v` describes; `leaf_prims(node, f)` calls f(id) for every primitive id of a leaf
/// (ids below `prim_count`).
template <TreeVisitor V, class LeafPrims>
EpoTree flatten_for_epo(const V& v, const LeafPrims& leaf_prims, size_t prim_count) {
  using Node = typename V::Node;
  EpoTree tree;
  std::vector<uint32_t> parent;
  std::vector<std::pair<uint32_t, uint32_t>> children, leaves;  // (parent, child), (primitive, leaf)
  std::vector<std::pair<Node, uint32_t>> todo{{v.root(), UINT32_MAX}};
  while (!todo.empty()) {  // a LIFO walk numbers every subtree contiguously: a preorder
    const auto [node, up] = todo.back();
    todo.pop_back();
    const auto i = uint32_t(tree.box.size());
    tree.box.push_back(v.box(node));
    parent.push_back(up);
    if (up != UINT32_MAX) children.push_back({up, i});
    if (v.is_leaf(node)) {
      tree.cost.push_back(float(v.count(node)));
      leaf_prims(node, [&](uint32_t id) { leaves.push_back({id, i}); });
      continue;
    }
    tree.cost.push_back(1.0f);
    v.children(node, [&](const Node& child) { todo.push_back({child, i}); });
  }
  std::vector<uint32_t> size(tree.box.size(), 1);
  for (size_t i = size.size(); i-- > 1;) size[parent[i]] += size[i];
  tree.end.resize(size.size());
  for (size_t i = 0; i < size.size(); ++i) tree.end[i] = uint32_t(i + size[i]);
  group_by_key(children, tree.box.size(), tree.child_begin, tree.child_list);
  group_by_key(leaves, prim_count, tree.leaf_begin, tree.leaf_list);
  return tree;
}

/// C(n) A(t inside n) summed over the nodes n whose subtree does not hold primitive `id` (triangle t).
double end_point_overlap_of(const EpoTree& tree, uint32_t id, const Triangle& t);

/// EPO of a tree over triangles: `triangle(id)` gives primitive id's triangle. 0 when the surface has no
/// area. Deterministic: per-triangle terms are summed in id order.
template <TreeVisitor V, class LeafPrims, class TriangleOf>
double end_point_overlap(const V& v, const LeafPrims& leaf_prims, size_t prim_count,
                         const TriangleOf& triangle) {
  const EpoTree tree = flatten_for_epo(v, leaf_prims, prim_count);
  std::vector<double> overlap(prim_count), area(prim_count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, prim_count, 1024),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t id = r.begin(); id < r.end(); ++id) {
                        const Triangle t = triangle(id);
                        area[id] = polygon_area(triangle_polygon(t));
                        overlap[id] = area[id] > 0.0 ? end_point_overlap_of(tree, uint32_t(id), t) : 0.0;
                      }
                    });
  double sum = 0.0, total = 0.0;
  for (size_t id = 0; id < prim_count; ++id) sum += overlap[id], total += area[id];
  return total > 0.0 ? sum / total : 0.0;
}

}  // namespace ab
