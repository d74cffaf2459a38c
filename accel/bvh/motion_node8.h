// The motion BVH's 8-wide node (Embree's AABBNodeMB4D, eight lanes as its BVH8 motion nodes): per child the
// box at the start of the child's time range, the motion of its corners to the range's end and the range
// itself; the ray's time interpolates all eight boxes at once with AVX2, then the 8-wide BVH's one slab test
// (walk8.h's Bvh8RayTest) takes them. A child whose range does not hold the ray's time is not entered.
#pragma once

#include <cstdint>
#include <vector>

#include "accel/bvh/motion_node.h"
#include "accel/bvh/walk8.h"
#include "accel/common/cache_line_allocator.h"

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace ab {

struct MotionBvh8RayTest;

/// One 8-wide motion node (576 bytes, nine cache lines). Lane k: the box at the start of its range (rows lo
/// x, y, z, hi x, y, z of `start`, widened as MotionBvhNode's), the corners' motion over the range (`motion`,
/// the same rows), the range [t0, t1] with scale = 1 / (t1 - t0), and as Bvh8Node a node index (count 0) or a
/// leaf's references [child, child + count). Unused lanes have the empty range t0 = 1 > t1 = 0 and an empty
/// box (lo +inf, hi -inf, no motion).
struct alignas(64) MotionBvh8Node {
  static constexpr int kWidth = 8;    ///< children per node
  using RayTest = MotionBvh8RayTest;  ///< the ray test of the eight lanes, for walk_bvh8 (walk8.h)

  float start[6][kWidth];     ///< box rows at the start of each lane's range
  float motion[6][kWidth];    ///< the rows' motion from the start to the end of the range
  float t0[kWidth];           ///< start of each lane's time range
  float t1[kWidth];           ///< end of each lane's time range
  float scale[kWidth];        ///< 1 / (t1 - t0)
  uint32_t child[kWidth];     ///< child node index (count 0) or first reference of a leaf
  uint32_t count[kWidth];     ///< references of a leaf lane, 0 for a node (or an unused lane)
  uint32_t pad[kWidth] = {};  ///< to a whole number of cache lines (zero: the node's bytes are its content)

  /// An empty node (every lane unused).
  MotionBvh8Node() {
    for (int k = 0; k < kWidth; ++k) clear(k);
  }
  /// Lane k from binary node n (a leaf keeps its references; an interior lane's child is set later).
  void set(int k, const MotionBvhNode& n) {
    for (int a = 0; a < 3; ++a) {
      start[a][k] = n.lo0[a], start[3 + a][k] = n.hi0[a];
      motion[a][k] = n.dlo[a], motion[3 + a][k] = n.dhi[a];
    }
    t0[k] = n.t0, t1[k] = n.t1, scale[k] = 1.0f / (n.t1 - n.t0);
    child[k] = n.is_leaf() ? n.offset : 0;
    count[k] = n.count;
  }
  /// Makes lane k unused.
  void clear(int k) {
    for (int a = 0; a < 3; ++a) {
      start[a][k] = kInf, start[3 + a][k] = -kInf;
      motion[a][k] = 0.0f, motion[3 + a][k] = 0.0f;
    }
    t0[k] = 1.0f, t1[k] = 0.0f, scale[k] = 1.0f;
    child[k] = 0, count[k] = 0;
  }

  /// The box of lane k at fraction f of its range.
  AABB box_at(int k, float f) const {
    AABB b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = start[a][k] + f * motion[a][k];
      b.hi[a] = start[3 + a][k] + f * motion[3 + a][k];
    }
    return b;
  }
  /// A box holding lane k over its whole range (what the statistics walk sees).
  AABB box(int k) const {
    AABB b = box_at(k, 0.0f);
    b.extend(box_at(k, 1.0f));
    return b;
  }
};
static_assert(sizeof(MotionBvh8Node) == 576);

/// The node array of an 8-wide motion BVH (node 0 is the root).
using MotionBvh8NodeArray = std::vector<MotionBvh8Node, CacheLineAllocator<MotionBvh8Node>>;

/// The ray test of an 8-wide motion node: the lanes whose range holds the ray's time, their boxes at that
/// time (f = (time - t0) * scale, box = start + f * motion: one FMA per row, within the margin of
/// kMotionBoxEps, see motion_node.h), then Bvh8RayTest's slab test of the eight boxes.
struct MotionBvh8RayTest {
  /// Prepares the per-ray data.
  explicit MotionBvh8RayTest(const Ray& ray) : boxes(ray), time(ray.time) {
#if defined(__AVX2__)
    time8 = _mm256_set1_ps(time);
#endif
  }

  /// Entry distances into t[0..7]; returns the mask of lanes entered at the ray's time.
  [[gnu::always_inline]] unsigned entries(const MotionBvh8Node& n, float limit, float* t) const {
#if defined(__AVX2__)
    const __m256 held = _mm256_and_ps(_mm256_cmp_ps(time8, _mm256_load_ps(n.t0), _CMP_GE_OQ),
                                      _mm256_cmp_ps(time8, _mm256_load_ps(n.t1), _CMP_LE_OQ));
    const __m256 f = _mm256_mul_ps(_mm256_sub_ps(time8, _mm256_load_ps(n.t0)), _mm256_load_ps(n.scale));
    const auto rows = [&](int row) {
#if defined(__FMA__)
      return _mm256_fmadd_ps(f, _mm256_load_ps(n.motion[row]), _mm256_load_ps(n.start[row]));
#else
      return _mm256_add_ps(_mm256_load_ps(n.start[row]), _mm256_mul_ps(f, _mm256_load_ps(n.motion[row])));
#endif
    };
    return boxes.entries_of_rows(rows, limit, t) & unsigned(_mm256_movemask_ps(held));
#else
    return entries_scalar(n, limit, t);
#endif
  }

  /// The same one lane at a time (the portable path): the boxes at the time into a Bvh8Node's rows.
  unsigned entries_scalar(const MotionBvh8Node& n, float limit, float* t) const {
    Bvh8Node boxes_at_time;
    unsigned held = 0;
    for (int k = 0; k < MotionBvh8Node::kWidth; ++k) {
      held |= unsigned(time >= n.t0[k] && time <= n.t1[k]) << k;
      const float f = (time - n.t0[k]) * n.scale[k];
      for (int row = 0; row < 6; ++row) boxes_at_time.bounds[row][k] = n.start[row][k] + f * n.motion[row][k];
    }
    return boxes.entries_scalar(boxes_at_time, limit, t) & held;
  }

  Bvh8RayTest boxes;  ///< the slab test of eight boxes
  float time;         ///< the ray's time
#if defined(__AVX2__)
  __m256 time8;  ///< the time in every lane
#endif
};

/// Collapses a binary motion BVH (MotionBvhBuilder's layout, not empty) into 8-wide nodes, greedily as the
/// static BVH's collapse (Wald, Benthin and Boulos 2008, section 3: keep opening the interior child of
/// largest area, here the area of its hull over its range, until there are eight); the children of a temporal
/// split become lanes with their own time ranges (Embree's AABBNodeMB4D). Leaves keep their references.
MotionBvh8NodeArray collapse_motion_bvh(const std::vector<MotionBvhNode>& binary);

}  // namespace ab
