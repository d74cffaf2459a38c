#include "accel/bvh/refit.h"

#include <immintrin.h>

#include <algorithm>

namespace ab {

namespace {

/// Prefetch distances in leaf-order lanes: the index triples (a mesh's) of the lanes kIndexAhead on and the
/// corners of the lanes kCornerAhead on are fetched ahead of use, so the gathers' latency (the ids are in
/// leaf order, the triangles in id order) is hidden behind the leaves written meanwhile.
constexpr size_t kIndexAhead = 32, kCornerAhead = 16;

/// Prefetches the cache lines of bytes [p, p + size).
void prefetch_bytes(const void* p, size_t size) {
  const char* c = static_cast<const char*>(p);
  _mm_prefetch(c, _MM_HINT_T0);
  if ((reinterpret_cast<uintptr_t>(c) & 63) + size > 64) _mm_prefetch(c + size - 1, _MM_HINT_T0);
}

/// Point p as four lanes (x, y, z, 0), read without touching the bytes after it.
__m128 lanes_of(const vec3& p) {
  return _mm_maskload_ps(&p.x, _mm_setr_epi32(-1, -1, -1, 0));
}

/// The corners of triangle `id` of a TrianglePrims (its copy in id order).
struct PrimsCorners {
  const TrianglePrims& prims;
  const Triangle& operator()(uint32_t id) const { return prims.triangle(id); }
  /// The three corners of triangle id as four lanes each.
  void lanes(uint32_t id, __m128* p) const {
    const Triangle& t = prims.triangle(id);
    p[0] = lanes_of(t.v0), p[1] = lanes_of(t.v1), p[2] = lanes_of(t.v2);
  }
  /// Prefetches what lane k's successors will read (ids: the n lanes' ids in leaf order).
  void prefetch(const uint32_t* ids, size_t k, size_t n) const {
    if (k + kCornerAhead >= n) return;
    const uint32_t id = ids[k + kCornerAhead];
    if (id != kInvalidId) prefetch_bytes(&prims.triangle(id), sizeof(Triangle));
  }
};

/// The corners of triangle `id` of an indexed mesh, through its index triple.
struct MeshCorners {
  const Mesh& mesh;
  Triangle operator()(uint32_t id) const { return mesh.triangle(id); }
  /// The three corners of triangle id as four lanes each.
  void lanes(uint32_t id, __m128* p) const {
    const glm::uvec3& t = mesh.triangles[id];
    for (int c = 0; c < 3; ++c) p[c] = lanes_of(mesh.vertices[t[c]]);
  }
  /// Prefetches what lane k's successors will read: their index triples, then their vertices.
  void prefetch(const uint32_t* ids, size_t k, size_t n) const {
    if (k + kIndexAhead < n && ids[k + kIndexAhead] != kInvalidId)
      prefetch_bytes(&mesh.triangles[ids[k + kIndexAhead]], sizeof(glm::uvec3));
    if (k + kCornerAhead >= n || ids[k + kCornerAhead] == kInvalidId) return;
    const glm::uvec3& t = mesh.triangles[ids[k + kCornerAhead]];
    for (int c = 0; c < 3; ++c) prefetch_bytes(&mesh.vertices[t[c]], sizeof(vec3));
  }
};

/// The box of four-lane minima and maxima (x, y, z lanes; the fourth unused).
AABB box_of_lanes(__m128 lo, __m128 hi) {
  alignas(16) float l[4], h[4];
  _mm_store_ps(l, lo);
  _mm_store_ps(h, hi);
  return {{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
}

/// Copies the triangles order[first, first + count) into tris (the same places) through `corners` and
/// returns their bounds (the one fold of both sources: the same bits whichever gives the triangles).
template <class Corners>
AABB copy_leaf_triangles(std::vector<Triangle>& tris, const std::vector<uint32_t>& order, uint32_t first,
                         uint32_t count, const Corners& corners) {
  AABB box;
  for (uint32_t k = first; k < first + count; ++k) {
    corners.prefetch(order.data(), k, order.size());
    tris[k] = corners(order[k]);
    box.extend(tris[k].bounds());
  }
  return box;
}

/// The rows x, y, z of four points (x, y, z, 0 each): their transpose.
[[gnu::always_inline]] inline Vec3T<Lanes4> rows_of(__m128 a, __m128 b, __m128 c, __m128 d) {
  _MM_TRANSPOSE4_PS(a, b, c, d);
  return {Lanes4(a), Lanes4(b), Lanes4(c)};
}

/// Stores one term of a block (its x, y and z rows).
[[gnu::always_inline]] inline void store_term(float (&row)[3][4], const Vec3T<Lanes4>& term) {
  _mm_store_ps(row[0], term.x.v);
  _mm_store_ps(row[1], term.y.v);
  _mm_store_ps(row[2], term.z.v);
}

/// Writes one block whose lanes j < m hold the triangles ids[0, m) (the rest the zero-area triangle, all
/// terms zero, as pack_leaf_blocks leaves them) and folds their corners into lo and hi. The four triangles'
/// corners are transposed into rows and their terms made on four lanes at once: triangle_terms' IEEE
/// operations lane by lane (e1 = v1 - v0, e2 = v2 - v0, n = cross(e1, e2) with triangle.h's operator- and
/// cross), so the bits Triangle4::set_lane stores for each. The terms are composed here rather than taken
/// as triangle_terms' TriangleTerms: GCC copies that returned aggregate through the stack with 32-byte moves
/// over 16-byte stores, a store-forwarding stall that made this function a third of the refit's time (1M
/// sphereflake, perf), while the terms in registers go straight to the block.
template <class Corners>
[[gnu::always_inline]] inline void write_block(Triangle4& block, const uint32_t* ids, uint32_t m,
                                               const Corners& corners, __m128& lo, __m128& hi) {
  __m128 q[4][3];  // q[lane][corner] = (x, y, z, 0)
  for (uint32_t j = 0; j < 4; ++j) {
    if (j >= m) {
      q[j][0] = q[j][1] = q[j][2] = _mm_setzero_ps();
      continue;
    }
    corners.lanes(ids[j], q[j]);
    for (int c = 0; c < 3; ++c) lo = _mm_min_ps(lo, q[j][c]), hi = _mm_max_ps(hi, q[j][c]);
    for (int c = 1; c < 3; ++c) {  // v0 + (v1 - v0) and v0 + (v2 - v0), as Triangle::bounds() holds them
      const __m128 k = _mm_add_ps(q[j][0], _mm_sub_ps(q[j][c], q[j][0]));
      lo = _mm_min_ps(lo, k), hi = _mm_max_ps(hi, k);
    }
  }
  const auto corner = [&](int c) { return rows_of(q[0][c], q[1][c], q[2][c], q[3][c]); };
  const Vec3T<Lanes4> v0 = corner(0);
  const Vec3T<Lanes4> e1 = corner(1) - v0;
  const Vec3T<Lanes4> e2 = corner(2) - v0;
  store_term(block.row[0], v0);
  store_term(block.row[1], e1);
  store_term(block.row[2], e2);
  store_term(block.row[3], cross(e1, e2));
}

/// Writes the (count + 3) / 4 blocks of the wide leaf from block `first` on through `corners` and returns
/// their bounds.
template <class Corners>
AABB write_leaf_blocks(Bvh8LeafBlocks& leaves, uint32_t first, uint32_t count, const Corners& corners) {
  __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);
  const uint32_t* ids = leaves.ids.data();
  for (uint32_t s = 0, b = first; s < count; s += 4, ++b) {
    for (size_t j = 0; j < 4; ++j) corners.prefetch(ids, 4 * size_t(b) + j, leaves.ids.size());
    write_block(leaves.blocks[b], ids + 4 * size_t(b), std::min(4u, count - s), corners, lo, hi);
  }
  return count > 0 ? box_of_lanes(lo, hi) : AABB{};
}

}  // namespace

AABB wide_node_box(const Bvh8Node& node) {
  AABB box;
  for (int a = 0; a < 3; ++a) {
    float lo = kInf, hi = -kInf;
    for (int j = 0; j < Bvh8Node::kWidth; ++j) {
      lo = std::min(lo, node.bounds[a][j]);
      hi = std::max(hi, node.bounds[3 + a][j]);
    }
    box.lo[a] = lo, box.hi[a] = hi;
  }
  return box;
}

AABB refresh_leaf_triangles(std::vector<Triangle>& tris, const std::vector<uint32_t>& order, uint32_t first,
                            uint32_t count, const TrianglePrims& prims) {
  return copy_leaf_triangles(tris, order, first, count, PrimsCorners{prims});
}

AABB refresh_leaf_triangles(std::vector<Triangle>& tris, const std::vector<uint32_t>& order, uint32_t first,
                            uint32_t count, const Mesh& mesh) {
  return copy_leaf_triangles(tris, order, first, count, MeshCorners{mesh});
}

AABB refresh_leaf_blocks(Bvh8LeafBlocks& leaves, uint32_t first, uint32_t count, const TrianglePrims& prims) {
  return write_leaf_blocks(leaves, first, count, PrimsCorners{prims});
}

AABB refresh_leaf_blocks(Bvh8LeafBlocks& leaves, uint32_t first, uint32_t count, const Mesh& mesh) {
  return write_leaf_blocks(leaves, first, count, MeshCorners{mesh});
}

}  // namespace ab
