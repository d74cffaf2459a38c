// The octree's configuration: each field's initializer is its default, read once from the parameters.
#pragma once

#include <cstddef>

#include "accel/common/leaf_refs.h"
#include "accel/core/params.h"

namespace ab {

/// Configuration of the octree.
struct OctreeConfig {
  size_t leaf_size = 8;  ///< a node with at most this many primitives is a leaf
  /// depth limit in levels that divide (a level whose largest child keeps more than 7/8 of a node of more
  /// than 64 primitives does not count; kMaxDepth levels in all); with auto_depth: the least
  int max_depth = 10;
  LeafCopies leaf_copies = LeafCopies::kAuto;  ///< copy triangles into leaf order (LeafRefs)
  bool auto_depth = true;  ///< depth limit max(max_depth, auto_octree_depth_limit(N)), at most kMaxDepth
  int bad_refines = 3;  ///< a node whose split is the bad_refines-th bad one on its path is a leaf (pbrt-v3)
  double ref_budget =
      32.0;  ///< the leaves hold at most this many references per primitive (build_with_budget)

  /// The deepest level traversal supports (its stack).
  static constexpr int kMaxDepth = 20;

  /// Reads every field from params.
  static OctreeConfig read(Params& params) {
    OctreeConfig c;
    params.read("leaf_size", c.leaf_size, 1, 1 << 20);
    params.read("max_depth", c.max_depth, 0, kMaxDepth);
    params.read("leaf_copies", c.leaf_copies, kLeafCopiesWords);
    params.read("auto_depth", c.auto_depth);
    params.read("bad_refines", c.bad_refines, 0, 1000);
    params.read("ref_budget", c.ref_budget, 1.0, 1e6);
    return c;
  }
};

}  // namespace ab
