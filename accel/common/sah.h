// The surface area heuristic (Goldsmith and Salmon 1987; MacDonald and Booth 1990) with the empty-space
// bonus of Wald and Havran 2006, written once: every SAH builder (the BVHs, the k-d trees, the BSP tree)
// prices its candidates with SahCosts, and the cost of every finished tree comes from the one statistics
// walk (tree_stats.h) through SahTreeCost. Also the centroid binning of the binned BVH builder (Wald 2007,
// "On fast construction of SAH-based bounding volume hierarchies").
#pragma once

#include "accel/core/aabb.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace ab {

/// The one SAH cost model of every builder: traversal and intersection costs, the empty-space bonus and
/// the SIMD block size. The normalized cost reported in BuildStats uses 1 and 1 (kUnitSahCosts).
struct SahCosts {
  float traversal = 1.0f;     ///< cost of visiting an interior node
  float intersection = 1.0f;  ///< cost of one primitive test (of one block, when block > 1)
  /// Wald and Havran 2006's bonus for cutting off empty space: a split with an empty side costs
  /// (1 - empty_bonus) times as much (their lambda). 0 for the BVHs, whose children are never empty.
  float empty_bonus = 0.0f;
  uint32_t block = 1;  ///< primitives tested at once (4 for SIMD triangle blocks, as in Embree)

  /// Tests needed for n primitives: ceil(n / block).
  float tests(size_t n) const { return float((n + block - 1) / block); }
  /// Cost of a leaf of n primitives (relative to its parent's area ratio, i.e. per unit probability).
  float leaf(size_t n) const { return intersection * tests(n); }
  /// Cost of splitting a node of area `parent_area` into children (area, count) pairs (areas relative to
  /// the parent's when parent_area is 1): lambda (traversal + intersection (A_l T_l + A_r T_r) / A).
  float split(float parent_area, float left_area, size_t left_n, float right_area, size_t right_n) const {
    const float lambda = (left_n == 0 || right_n == 0) ? 1.0f - empty_bonus : 1.0f;
    if (!(parent_area > 0.0f)) return lambda * (traversal + intersection * (tests(left_n) + tests(right_n)));
    return lambda * (traversal + intersection * (left_area * tests(left_n) + right_area * tests(right_n)) / parent_area);
  }
};

/// Default costs: traversal 1, intersection 1 (the normalization used in reports).
inline constexpr SahCosts kUnitSahCosts{};

/// One bin of Wald's binned builder: the bounds of the primitives whose centroid fell in it, and their count.
struct SahBin {
  AABB bounds;
  uint32_t count = 0;

  /// Adds a primitive with bounds b.
  void add(const AABB& b) {
    bounds.extend(b);
    ++count;
  }
  /// Merges another bin (exact: min, max and integer sum, so any merge order gives the same bits).
  void merge(const SahBin& o) {
    bounds.extend(o.bounds);
    count += o.count;
  }
};

/// Maps a centroid coordinate to one of `bins` bins over [lo, lo + extent] (Wald 2007, eq. for k1).
struct BinMapping {
  vec3 lo{0.0f};
  vec3 scale{0.0f};  ///< bins / extent per axis (0 for a flat axis: everything in bin 0)
  int bins = 1;

  /// Mapping over centroid bounds cb with `bins` bins per axis.
  BinMapping(const AABB& cb, int n) : lo(cb.lo), bins(n) {
    const vec3 e = cb.extent();
    for (int a = 0; a < 3; ++a) scale[a] = e[a] > 0.0f ? float(n) * (1.0f - 0x1p-12f) / e[a] : 0.0f;
  }
  /// Bin of coordinate c along axis a (clamped to [0, bins-1]).
  int bin(int a, float c) const {
    const int k = int((c - lo[a]) * scale[a]);
    return std::clamp(k, 0, bins - 1);
  }
};

/// Result of a split search: axis, position (a bin boundary or a sorted index) and SAH cost.
struct SahSplit {
  int axis = -1;       ///< -1: no valid split found
  int position = 0;    ///< bins [0, position) go left (binned), or sorted index split (sweep)
  float cost = kInf;   ///< SAH cost of the split (with the costs used)
};

/// Best split among the n bin boundaries of one axis, for any bin representation: box_of(k) and count_of(k)
/// give bin k, Box (starting from `empty`) has extend(box) and area(). Sweeps right to left to get suffix
/// areas, then left to right evaluating every boundary (Wald 2007). Updates best when a cheaper split is found.
template <class Box, class BoxOf, class CountOf>
inline void best_bin_split_of(int n, int axis, float parent_area, const SahCosts& costs, SahSplit& best,
                              const Box& empty, BoxOf box_of, CountOf count_of) {
  std::array<float, 256> right_area;     // only [1, n) is written and read: no zeroing (this runs per node)
  std::array<uint32_t, 256> right_count;
  Box acc = empty;
  uint32_t cnt = 0;
  for (int i = n - 1; i > 0; --i) {
    acc.extend(box_of(i));
    cnt += count_of(i);
    right_area[i] = acc.area();
    right_count[i] = cnt;
  }
  // The cheapest boundary minimizes left_area * left_count + right_area * right_count (the cost without
  // its constant terms, so no division per boundary); its full cost is computed once.
  acc = empty;
  cnt = 0;
  float best_weighted = kInf, best_left_area = 0.0f, best_right_area = 0.0f;
  int best_i = 0;
  uint32_t best_left = 0;
  for (int i = 1; i < n; ++i) {
    acc.extend(box_of(i - 1));
    cnt += count_of(i - 1);
    if (cnt == 0 || right_count[i] == 0) continue;
    const float left_area = acc.area();
    const float weighted = left_area * float(cnt) + right_area[i] * float(right_count[i]);
    if (weighted < best_weighted) {
      best_weighted = weighted, best_i = i, best_left = cnt;
      best_left_area = left_area, best_right_area = right_area[i];
    }
  }
  if (best_i == 0) return;
  const float c = costs.split(parent_area, best_left_area, best_left, best_right_area, right_count[best_i]);
  if (c < best.cost) best = {axis, best_i, c};
}

/// best_bin_split_of over an array of SahBin.
inline void best_bin_split(const SahBin* bins, int n, int axis, float parent_area, const SahCosts& costs,
                           SahSplit& best) {
  best_bin_split_of(
      n, axis, parent_area, costs, best, AABB{}, [&](int k) -> const AABB& { return bins[k].bounds; },
      [&](int k) { return bins[k].count; });
}

/// Normalized SAH cost of a finished tree given per-node areas: sum over interior nodes of
/// traversal * area + sum over leaves of intersection * count * area, divided by the root area.
/// The statistics walk (tree_stats.h) accumulates with add_interior/add_leaf and reads cost().
class SahTreeCost {
 public:
  /// Starts with the root's area and the costs to use (kUnitSahCosts for reports).
  SahTreeCost(float root_area, SahCosts costs = kUnitSahCosts) : root_area_(root_area), costs_(costs) {}
  /// Adds an interior node of the given area.
  void add_interior(float area) { sum_ += double(costs_.traversal) * area; }
  /// Adds a leaf of the given area and primitive count.
  void add_leaf(float area, size_t n) { sum_ += double(costs_.intersection) * double(n) * area; }
  /// Normalized cost (0 when the root has no area).
  double cost() const { return root_area_ > 0.0f ? sum_ / double(root_area_) : 0.0; }

 private:
  float root_area_;
  SahCosts costs_;
  double sum_ = 0.0;
};

}  // namespace ab
