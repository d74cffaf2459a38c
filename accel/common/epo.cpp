#include "accel/common/epo.h"

namespace ab {

void group_by_key(const std::vector<std::pair<uint32_t, uint32_t>>& pairs, size_t n,
                  std::vector<uint32_t>& begin, std::vector<uint32_t>& list) {
  begin.assign(n + 1, 0);
  for (const auto& [key, value] : pairs) ++begin[key + 1];
  for (size_t k = 0; k < n; ++k) begin[k + 1] += begin[k];
  list.resize(pairs.size());
  std::vector<uint32_t> next(begin.begin(), begin.end() - 1);
  for (const auto& [key, value] : pairs) list[next[key]++] = value;
}

namespace {

/// True when a leaf of node n's subtree holds primitive id.
bool subtree_holds(const EpoTree& tree, uint32_t n, uint32_t id) {
  for (uint32_t k = tree.leaf_begin[id]; k < tree.leaf_begin[id + 1]; ++k)
    if (n <= tree.leaf_list[k] && tree.leaf_list[k] < tree.end[n]) return true;
  return false;
}

/// Area of the part of t inside box (t's whole area when its bounds are inside).
double area_inside(const Triangle& t, const AABB& tb, double whole, const AABB& box) {
  if (box.contains(tb.lo) && box.contains(tb.hi)) return whole;
  ClipPolygon poly = triangle_polygon(t);
  clip_polygon_to_box(poly, box);
  return poly.n >= 3 ? polygon_area(poly) : 0.0;
}

}  // namespace

double end_point_overlap_of(const EpoTree& tree, uint32_t id, const Triangle& t) {
  const AABB tb = t.bounds();
  const double whole = polygon_area(triangle_polygon(t));
  thread_local std::vector<uint32_t> todo;
  todo.assign(1, 0);
  double sum = 0.0;
  while (!todo.empty()) {
    const uint32_t n = todo.back();
    todo.pop_back();
    if (!tree.box[n].overlaps(tb)) continue;
    if (!subtree_holds(tree, n, id)) {
      const double a = area_inside(t, tb, whole, tree.box[n]);
      if (!(a > 0.0)) continue;  // the children's boxes lie in this one: they hold none of t either
      sum += double(tree.cost[n]) * a;
    }
    for (uint32_t k = tree.child_begin[n]; k < tree.child_begin[n + 1]; ++k)
      todo.push_back(tree.child_list[k]);
  }
  return sum;
}

}  // namespace ab
