// The configuration of bvh-sphere: the binned-SAH builder's settings (its topology is bvh-sah's binary
// tree), read once from the parameters and handed to the builder as a BvhSahConfig.
#pragma once

#include "accel/bvh/config.h"
#include "accel/core/params.h"

namespace ab {

/// bvh-sphere: bvh-sah's binary tree (width 2) with a sphere per node.
struct BvhSphereConfig : BvhSahTreeConfig {
  int bins = 32;  ///< bins per axis of the binned SAH builder

  /// Reads every field (max_leaf_size, traversal_cost, intersection_cost, max_depth, bins).
  static BvhSphereConfig read(Params& params) {
    BvhSphereConfig c;
    c.read_sah_tree(params);
    params.read("bins", c.bins, 2, 256);
    return c;
  }

  /// The builder's Config: the same settings, binary.
  BvhSahConfig builder() const {
    BvhSahConfig b;
    static_cast<BvhSahTreeConfig&>(b) = *this;
    b.bins = bins;
    b.width = 2;
    return b;
  }
};

}  // namespace ab
