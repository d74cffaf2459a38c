#include "accel/bvh/refit.h"

#include <immintrin.h>

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
  // Lanes are written in place (padding lanes keep the zero-area triangle of the build); the bounds of a
  // full block come from four-lane min and max over its three corners, a partial block's lane by lane.
  __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);  // lanes x, y, z (the fourth unused)
  for (uint32_t s = 0, b = 0; s < count; s += 4, ++b) {
    Triangle4& block = blocks[b];
    const uint32_t m = std::min(4u, count - s);
    for (uint32_t j = 0; j < m; ++j) {
      const Triangle& t = prims.triangle(ids[s + j]);
      block.set_lane(int(j), t);  // the kernel's terms, as pack_leaf_blocks stores them
      const vec3* corners[3] = {&t.v0, &t.v1, &t.v2};
      for (int c = 0; c < 3; ++c) {
        const __m128 p = _mm_setr_ps(corners[c]->x, corners[c]->y, corners[c]->z, 0.0f);
        lo = _mm_min_ps(lo, p);
        hi = _mm_max_ps(hi, p);
      }
    }
  }
  alignas(16) float l[4], h[4];
  _mm_store_ps(l, lo);
  _mm_store_ps(h, hi);
  AABB box;
  if (count > 0) box = {{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
  return box;
}

}  // namespace ab
