// Centroid binning (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"): the map
// from a centroid coordinate to one of k equal-width bins over the node's centroid bounds, whose bin
// boundaries are the split candidates of a binned SAH builder.
#pragma once

#include <algorithm>

#include "accel/core/aabb.h"

namespace ab {

/// Maps a centroid coordinate to one of `bins` bins over [lo, lo + extent] (Wald 2007, eq. for k1).
struct BinMapping {
  vec3 lo{0.0f};     ///< minimum of the centroid bounds
  vec3 scale{0.0f};  ///< bins / extent per axis (0 for a flat axis: everything in bin 0)
  int bins = 1;      ///< bins per axis

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

}  // namespace ab
