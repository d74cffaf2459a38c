#include "accel/bvh/refit.h"

#include <algorithm>

namespace ab {

void refit_binary_interiors(BvhNodeArray& nodes) {
  for (size_t i = nodes.size(); i-- > 0;) {
    BvhNode& n = nodes[i];
    if (i == 1 || n.is_leaf()) continue;
    const BvhNode& l = nodes[n.offset];
    const BvhNode& r = nodes[n.offset + 1];
    for (int a = 0; a < 3; ++a) {
      n.lo[a] = std::min(l.lo[a], r.lo[a]);
      n.hi[a] = std::max(l.hi[a], r.hi[a]);
    }
  }
}

void refit_wide_interiors(Bvh8NodeArray& wide) {
  for (size_t i = wide.size(); i-- > 0;) {
    Bvh8Node& node = wide[i];
    for (int k = 0; k < Bvh8Node::kWidth; ++k) {
      if (node.count[k] != 0 || node.child[k] == 0) continue;  // a leaf lane or an unused lane
      const Bvh8Node& c = wide[node.child[k]];
      // Unused lanes of c hold the empty box, which leaves the union unchanged.
      for (int a = 0; a < 3; ++a) {
        float lo = kInf, hi = -kInf;
        for (int j = 0; j < Bvh8Node::kWidth; ++j) {
          lo = std::min(lo, c.bounds[a][j]);
          hi = std::max(hi, c.bounds[3 + a][j]);
        }
        node.bounds[a][k] = lo;
        node.bounds[3 + a][k] = hi;
      }
    }
  }
}

AABB refresh_leaf_triangles(Triangle* out, const uint32_t* ids, uint32_t count, const TrianglePrims& prims) {
  AABB box;
  for (uint32_t k = 0; k < count; ++k) {
    out[k] = prims.triangle(ids[k]);
    box.extend(out[k].bounds());
  }
  return box;
}

AABB refresh_leaf_blocks(Triangle4* blocks, const uint32_t* ids, uint32_t count, const TrianglePrims& prims) {
  AABB box;
  for (uint32_t s = 0, b = 0; s < count; s += 4, ++b) {
    Triangle quad[4] = {};
    const uint32_t m = std::min(4u, count - s);
    for (uint32_t j = 0; j < m; ++j) {
      quad[j] = prims.triangle(ids[s + j]);
      box.extend(quad[j].bounds());
    }
    blocks[b] = Triangle4::pack(std::span<const Triangle>(quad, m));
  }
  return box;
}

}  // namespace ab
