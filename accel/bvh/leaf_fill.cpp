#include "accel/bvh/leaf_fill.h"

#include <algorithm>

namespace ab {

namespace {

constexpr uint32_t kBlock = 4;  ///< triangles per leaf block (Triangle4)

/// Where a leaf of n triangles splits: the first `left` of idx (positions in the leaf, sorted on the split's
/// axis) go to one lane, the rest to the other.
struct LeafSplit {
  uint32_t left = 0;  ///< 0: no split
  float cost = kInf;  ///< summed area of the two boxes
  uint32_t idx[Bvh8Node::kWidth];
};

/// The boxes of n triangles (ids), each clipped to the leaf's box.
void clipped_boxes(const uint32_t* ids, uint32_t n, const AABB& leaf, const TrianglePrims& prims, AABB* box) {
  for (uint32_t j = 0; j < n; ++j) box[j] = AABB::intersection(prims.bounds(ids[j]), leaf);
}

/// Sorts idx[0, n) by the boxes' centres on axis: an insertion sort (n <= 8), stable, so ties keep the
/// leaf's order and the split is the same on every run.
void sort_on_axis(const AABB* box, uint32_t n, int axis, uint32_t* idx) {
  float key[Bvh8Node::kWidth];
  for (uint32_t j = 0; j < n; ++j) {
    const float c = box[j].lo[axis] + box[j].hi[axis];
    uint32_t i = j;
    for (; i > 0 && key[i - 1] > c; --i) key[i] = key[i - 1], idx[i] = idx[i - 1];
    key[i] = c;
    idx[i] = j;
  }
}

/// The best split of n boxes (5 to 8) into two sides of at most one block each, over the three axes.
LeafSplit best_split(const AABB* box, uint32_t n) {
  LeafSplit best;
  for (int axis = 0; axis < 3; ++axis) {
    uint32_t idx[Bvh8Node::kWidth];
    sort_on_axis(box, n, axis, idx);
    AABB right[Bvh8Node::kWidth + 1];
    for (uint32_t j = n; j-- > n - kBlock;) right[j] = right[j + 1], right[j].extend(box[idx[j]]);
    AABB left;
    for (uint32_t j = 0; j < kBlock; ++j) {
      left.extend(box[idx[j]]);
      const uint32_t l = j + 1;
      if (n - l > kBlock) continue;
      const float cost = left.area() + right[l].area();
      if (cost < best.cost) {
        best.left = l, best.cost = cost;
        std::copy(idx, idx + n, best.idx);
      }
    }
  }
  return best;
}

/// The leaf lane to split next: the largest box among the leaves of five to eight triangles (-1: none).
int lane_to_split(const Bvh8Node& node) {
  int pick = -1;
  float area = -1.0f;
  for (int k = 0; k < Bvh8Node::kWidth; ++k) {
    const uint32_t n = node.count[k];
    if (n <= kBlock || n > 2 * kBlock) continue;
    if (const float a = node.box(k).area(); a > area) pick = k, area = a;
  }
  return pick;
}

/// Writes box into lane k of node.
void set_lane_box(Bvh8Node& node, int k, const AABB& box) {
  for (int a = 0; a < 3; ++a) {
    node.bounds[a][k] = box.lo[a];
    node.bounds[3 + a][k] = box.hi[a];
  }
}

/// Splits leaf lane k into lanes k and f (unused) at its best split; ids[k] and ids[f] then point into
/// ids.own. Returns false (the node unchanged) when no split has a finite cost or a side's box would be
/// empty (a triangle's bounds outside the leaf's box: the lane would read as unused).
bool split_lane(Bvh8Node& node, int k, int f, const TrianglePrims& prims, NodeLaneIds& ids) {
  const uint32_t n = node.count[k];
  AABB box[Bvh8Node::kWidth];
  clipped_boxes(ids.lane[k], n, node.box(k), prims, box);
  const LeafSplit s = best_split(box, n);
  if (s.left == 0) return false;
  const uint32_t* idx = s.idx;
  uint32_t* own = ids.own + k * Bvh8Node::kWidth;
  AABB sides[2];
  for (uint32_t j = 0; j < n; ++j) sides[j < s.left ? 0 : 1].extend(box[idx[j]]);
  if (sides[0].empty() || sides[1].empty()) return false;
  for (uint32_t j = 0; j < n; ++j) own[j] = ids.lane[k][idx[j]];
  set_lane_box(node, k, sides[0]);
  set_lane_box(node, f, sides[1]);
  node.count[k] = s.left;
  node.count[f] = n - s.left;
  node.child[f] = node.child[k];
  ids.lane[k] = own;
  ids.lane[f] = own + s.left;
  return true;
}

}  // namespace

void fill_free_lanes(Bvh8Node& node, std::span<const uint32_t> order, const TrianglePrims& prims,
                     NodeLaneIds& ids) {
  for (int k = 0; k < Bvh8Node::kWidth; ++k)
    ids.lane[k] = node.count[k] > 0 ? order.data() + node.child[k] : nullptr;
  for (int f = 0; f < Bvh8Node::kWidth; ++f) {
    if (node.used(f)) continue;
    const int k = lane_to_split(node);
    if (k < 0 || !split_lane(node, k, f, prims, ids)) break;
  }
}

}  // namespace ab
