// Binned SAH planes for the large nodes of the SAH k-d tree, the hybrid of the fast k-d builders: Shevtsov,
// Soupikov and Kapustin 2007, "Highly parallel fast KD-tree construction for interactive ray tracing of
// dynamic scenes" (per axis, counts of the references' clipped minima and maxima in bins over the node,
// the bins' boundaries as candidate planes, then exact classification), Hunt, Mark and Stoll 2006, "Fast
// kd-tree construction with an adaptive error-bounded heuristic" (sampled cost at the top, exact below),
// and Wald and Havran 2006, section 5 (the sorted event lists made per subtree instead of once at the root).
// A node above the threshold keeps its references with their clipped boxes (KdBoxNode, box_node.h); the bins
// are summed in parallel (integer counts, minima and maxima: the same result in any order, so the same tree
// for any thread count). Besides the bins' boundaries, the planes at the references' extent on each axis are
// priced exactly (their counts are exact), so the empty space around the geometry is cut off as the exact
// sweep would.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "accel/kdtree/box_node.h"
#include "accel/kdtree/sah_sweep.h"

namespace ab {

/// Bins per axis of the binned planes.
inline constexpr int kKdBins = 64;

/// One axis's bins: how many references start (clipped minimum) and end (clipped maximum) in each bin,
/// and the references' extent along the axis.
struct KdAxisBins {
  std::array<uint32_t, kKdBins> starts{};  ///< references whose minimum falls in the bin
  std::array<uint32_t, kKdBins> ends{};    ///< references whose maximum falls in the bin
  float lo = kInf;                         ///< smallest minimum
  float hi = -kInf;                        ///< largest maximum
};

/// The three axes' bins of a node.
using KdBins = std::array<KdAxisBins, 3>;

/// Adds the counts of `from` to `into`.
inline void merge_kd_bins(KdBins& into, const KdBins& from) {
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < kKdBins; ++b) {
      into[a].starts[b] += from[a].starts[b];
      into[a].ends[b] += from[a].ends[b];
    }
    into[a].lo = std::min(into[a].lo, from[a].lo);
    into[a].hi = std::max(into[a].hi, from[a].hi);
  }
}

/// Bins the clipped boxes of a node (in parallel over its references).
inline KdBins bin_kd_node(const KdBoxNode& node) {
  std::array<float, 3> scale{};
  for (int a = 0; a < 3; ++a) {
    const float e = node.box.hi[a] - node.box.lo[a];
    scale[a] = e > 0.0f ? float(kKdBins) / e : 0.0f;
  }
  auto bin_range = [&](const tbb::blocked_range<size_t>& r, KdBins bins) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const AABB& cb = node.bounds[i];
      for (int a = 0; a < 3; ++a) {
        const float lo = node.box.lo[a];
        ++bins[a].starts[std::clamp(int((cb.lo[a] - lo) * scale[a]), 0, kKdBins - 1)];
        ++bins[a].ends[std::clamp(int((cb.hi[a] - lo) * scale[a]), 0, kKdBins - 1)];
        bins[a].lo = std::min(bins[a].lo, cb.lo[a]);
        bins[a].hi = std::max(bins[a].hi, cb.hi[a]);
      }
    }
    return bins;
  };
  return tbb::parallel_reduce(tbb::blocked_range<size_t>(0, node.bounds.size(), 4096), KdBins{}, bin_range,
                              [](KdBins a, const KdBins& b) {
                                merge_kd_bins(a, b);
                                return a;
                              });
}

/// The cheapest binned plane of a large node (and the cheapest one with progress, for max_leaf): the
/// bins' boundaries with the counts of the bins (a reference is on the left of boundary j when its
/// minimum lies in a bin below j, on the right when its maximum lies in bin j or above), and the two planes
/// at the references' extent, which cut off empty space (counts exact: all on one side).
inline KdSahChoice find_binned_kd_plane(const SahCosts& costs, const KdBoxNode& node) {
  KdSahChoice best;
  if (!(frame_area(node.box) > 0.0f)) return best;
  const uint32_t n = uint32_t(node.ids.size());
  const KdBins bins = bin_kd_node(node);
  for (int a = 0; a < 3; ++a) {
    const KdAxisAreas ar(node.box, a);
    const float lo = node.box.lo[a], hi = node.box.hi[a];
    if (!(hi > lo)) continue;
    const KdAxisBins& b = bins[a];
    auto inside = [&](float p) { return p > lo && p < hi; };
    // Empty space below the geometry (planar references at the plane go right) and above it.
    if (inside(b.lo)) evaluate_kd_plane(costs, ar, a, b.lo, 0, 0, n, n, best, false);
    if (inside(b.hi)) evaluate_kd_plane(costs, ar, a, b.hi, n, 0, 0, n, best, true);
    uint32_t nl = 0, nr = n;
    for (int j = 1; j < kKdBins; ++j) {
      nl += b.starts[j - 1];
      nr -= b.ends[j - 1];
      const float p = lo + (hi - lo) * (float(j) / float(kKdBins));
      if (inside(p) && p > b.lo && p < b.hi) evaluate_kd_plane(costs, ar, a, p, nl, 0, nr, n, best, true);
    }
  }
  return best;
}

/// The side of a reference with clipped extent [lo, hi] on the split axis (bit 0 left, bit 1 right), Wald
/// and Havran's classification: ending at or before the plane left only, starting at or after it right
/// only, planar in it on the chosen side.
inline uint8_t kd_side(float lo, float hi, float split, bool planar_left) {
  if (lo == hi) return lo < split ? 1 : lo > split ? 2 : planar_left ? 1 : 2;
  return hi <= split ? 1 : lo >= split ? 2 : 3;
}

}  // namespace ab
