// The node of the 8-wide BVH that bvh-sah traverses by default (Wald, Benthin and Boulos 2008, "Getting rid
// of packets: efficient SIMD single-ray traversal using multi-branching BVHs"; Dammertz, Hanika and Keller
// 2008, "Shallow bounding volume hierarchies for fast SIMD ray tracing of incoherent rays").
#pragma once

#include <cstdint>
#include <vector>

#include "accel/common/cache_line_allocator.h"
#include "accel/core/aabb.h"

namespace ab {

struct Bvh8RayTest;

/// One node of the 8-wide BVH: the children's boxes as structure-of-arrays rows (lo x, y, z, then hi x,
/// y, z; eight lanes each) and per child either a node index (count 0) or a leaf's range [child, child +
/// count) of the leaf-ordered primitives. Unused lanes hold an empty box (lo +inf, hi -inf), which no ray
/// enters. 256 bytes: four cache lines.
struct alignas(64) Bvh8Node {
  static constexpr int kWidth = 8;  ///< children per node
  using RayTest = Bvh8RayTest;      ///< the ray test of the eight boxes, for walk_bvh8 (walk8.h)
  float bounds[6][kWidth];          ///< lo x, y, z and hi x, y, z rows
  uint32_t child[kWidth];           ///< child node index (count 0) or first primitive (or block) of a leaf
  uint32_t count[kWidth];           ///< primitives of a leaf lane, 0 for a node (or an unused lane)

  /// True when lane k holds a child.
  bool used(int k) const { return bounds[0][k] <= bounds[3][k]; }
  /// The box of lane k.
  AABB box(int k) const {
    return {{bounds[0][k], bounds[1][k], bounds[2][k]}, {bounds[3][k], bounds[4][k], bounds[5][k]}};
  }
};
static_assert(sizeof(Bvh8Node) == 256, "BVH8 nodes are 256 bytes");

/// The node array of an 8-wide BVH (node 0 is the root).
using Bvh8NodeArray = std::vector<Bvh8Node, CacheLineAllocator<Bvh8Node>>;

}  // namespace ab
