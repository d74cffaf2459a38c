// The surface area heuristic (Goldsmith and Salmon 1987; MacDonald and Booth 1990) with the empty-space
// bonus of Wald and Havran 2006, written once: every SAH builder (the BVHs, the k-d trees, the BSP tree)
// prices its candidates with SahCosts, and the cost of every finished tree comes from the one statistics
// walk (tree_stats.h) through SahTreeCost. (The centroid binning of the binned BVH builder is binning.h.)
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "accel/core/aabb.h"

namespace ab {

/// The power of two by which a node's edge lengths e are multiplied before its areas are made: the SAH
/// prices ratios of areas, which a power of two leaves exact. 1 when the longest edge lies in [2^-40, 2^40],
/// so ordinary nodes keep their own bits; beyond, the one that brings it into [1, 2), since there the squares
/// of the edges underflow (below about 1e-19) or overflow (above about 1e19) and every area is 0 or inf.
inline float area_frame(const vec3& e) {
  const float m = std::max({e.x, e.y, e.z});
  if (!(m > 0.0f) || !std::isfinite(m) || (m >= 0x1p-40f && m <= 0x1p40f)) return 1.0f;
  return std::ldexp(1.0f, std::clamp(-std::ilogb(m), -126, 127));
}

/// Surface area of box in its area_frame (the same ratios as its own areas, at any scale).
inline float frame_area(const AABB& box) {
  const vec3 e = box.extent();
  return area_of_extent(e * area_frame(e));
}

/// The one SAH cost model of every builder: traversal and intersection costs, the empty-space bonus and
/// the SIMD block size. The normalized cost reported in BuildStats uses 1 and 1 (kUnitSahCosts).
struct SahCosts {
  float traversal = 1.0f;     ///< cost of visiting an interior node
  float intersection = 1.0f;  ///< cost of one primitive test (of one block, when block > 1)
  /// Wald and Havran 2006's bonus for cutting off empty space: a split with an empty side costs
  /// (1 - empty_bonus) times as much (their lambda). 0 for the BVHs, whose children are never empty.
  float empty_bonus = 0.0f;
  uint32_t block = 1;  ///< primitives tested at once (4 for SIMD triangle blocks, as in Embree)

  /// Tests needed for n primitives: ceil(n / block) (a shift for a power-of-two block: the cost is priced for
  /// every candidate plane, and an integer division is slow).
  float tests(size_t n) const {
    // (A count below 2^63 converts from a signed integer to the same float in one instruction; an unsigned
    // one takes a test and a branch, and the bsp prices a few hundred planes a node.)
    if (block == 1) return float(int64_t(n));
    if (std::has_single_bit(block)) return float((n + block - 1) >> std::countr_zero(block));
    return float((n + block - 1) / block);
  }
  /// Cost of a leaf of n primitives (relative to its parent's area ratio, i.e. per unit probability).
  float leaf(size_t n) const { return intersection * tests(n); }
  /// Cost of splitting a node of area `parent_area` into children (area, count) pairs (areas relative to
  /// the parent's when parent_area is 1): lambda (traversal + intersection (A_l T_l + A_r T_r) / A).
  [[gnu::always_inline]] float split(float parent_area, float left_area, size_t left_n, float right_area,
                                     size_t right_n) const {
    const float lambda = (left_n == 0 || right_n == 0) ? 1.0f - empty_bonus : 1.0f;
    if (!(parent_area > 0.0f)) return lambda * (traversal + intersection * (tests(left_n) + tests(right_n)));
    return lambda * (traversal +
                     intersection * (left_area * tests(left_n) + right_area * tests(right_n)) / parent_area);
  }
};

/// Default costs: traversal 1, intersection 1 (the normalization used in reports).
inline constexpr SahCosts kUnitSahCosts{};

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
