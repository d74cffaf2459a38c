// The octree's configuration: each field's initializer is its default, read once from the parameters.
#pragma once

#include <cstddef>

#include "accel/common/leaf_refs.h"
#include "accel/core/params.h"

namespace ab {

/// Configuration of the octree.
struct OctreeConfig {
  size_t leaf_size = 8;                        ///< a node with at most this many primitives is a leaf
  int max_depth = 10;                          ///< deepest level of subdivision
  LeafCopies leaf_copies = LeafCopies::kAuto;  ///< copy triangles into leaf order (LeafRefs)

  /// Reads every field from params.
  static OctreeConfig read(Params& params) {
    OctreeConfig c;
    params.read("leaf_size", c.leaf_size, 1, 1 << 20);
    params.read("max_depth", c.max_depth, 0, 20);
    params.read("leaf_copies", c.leaf_copies, kLeafCopiesWords);
    return c;
  }
};

}  // namespace ab
