// The configuration of bvh-sbvh (sbvh.cpp): bvh-sah's configuration plus the spatial splits' own (bins,
// overlap threshold, reference budget).
#pragma once

#include "accel/bvh/config.h"
#include "accel/core/params.h"

namespace ab {

/// bvh-sbvh: binned SAH with spatial splits (Stich, Friedrich and Dietrich 2009), 8-wide by default:
/// bvh-sah's settings (object-split bins over the references' centroids, width, collapse) plus the spatial
/// splits'.
struct BvhSbvhConfig : BvhSahConfig {
  int spatial_bins = 16;  ///< spatial-split bins per axis (over the node's box; fewer than bins: each costs a
                          ///< clip per straddling reference)
  /// Spatial splits are tried at a node whose best object split's children overlap by more than alpha
  /// times the root's surface area (the paper's alpha; 1e-5 is its recommended value).
  double alpha = 1e-5;
  /// The reference budget: at most ref_budget x N references over N primitives (spatial splits stop where
  /// a node's share is used up), so hostile inputs stay bounded; 1 allows no spatial split.
  double ref_budget = 1.5;

  /// Reads every field.
  static BvhSbvhConfig read(Params& params) {
    BvhSbvhConfig c;
    static_cast<BvhSahConfig&>(c) = BvhSahConfig::read(params);
    params.read("spatial_bins", c.spatial_bins, 2, 256);
    params.read("alpha", c.alpha, 0.0, 1.0);
    params.read("ref_budget", c.ref_budget, 1.0, 4.0);
    return c;
  }
};

}  // namespace ab
