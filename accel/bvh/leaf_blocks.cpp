#include "accel/bvh/leaf_blocks.h"

#include <algorithm>

namespace ab {

Bvh8LeafBlocks pack_leaf_blocks(Bvh8NodeArray& wide, std::span<const uint32_t> order,
                                const TrianglePrims& prims) {
  Bvh8LeafBlocks out;
  for (Bvh8Node& node : wide) {
    for (int k = 0; k < Bvh8Node::kWidth; ++k) {
      if (node.count[k] == 0) continue;
      const uint32_t first = node.child[k], n = node.count[k];
      node.child[k] = uint32_t(out.blocks.size());
      for (uint32_t s = 0; s < n; s += 4) {
        Triangle quad[4] = {};  // only the first m are read; zeroed so no lane is uninitialized
        const uint32_t m = std::min(4u, n - s);
        for (uint32_t j = 0; j < 4; ++j) {
          if (j < m) quad[j] = prims.triangle(order[first + s + j]);
          out.ids.push_back(j < m ? order[first + s + j] : kInvalidId);
        }
        out.blocks.push_back(Triangle4::pack(std::span<const Triangle>(quad, m)));
      }
    }
  }
  return out;
}

}  // namespace ab
