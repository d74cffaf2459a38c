// The default depth limit of the space-partitioning trees that split by planes (k-d trees, BSP tree).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace ab {

/// Depth limit for n primitives when the configuration leaves it at 0: 8 + 1.3 log2 N (Havran 2000; pbrt).
inline int auto_depth_limit(size_t n) {
  return int(std::lround(8.0 + 1.3 * std::log2(double(std::max<size_t>(n, 1)))));
}

/// The octree's depth limit for n primitives: the same bound in octree levels, each of which is three binary
/// plane levels: round((8 + 1.3 log2 N) / 3), 10 up to about 100k primitives and 13 at 10M.
inline int auto_octree_depth_limit(size_t n) {
  return int(std::lround((8.0 + 1.3 * std::log2(double(std::max<size_t>(n, 1)))) / 3.0));
}

}  // namespace ab
