// The node of the bounding-sphere hierarchy (bvh-sphere): the binary BVH's node (node.h) with a sphere in
// place of the box, in the same layout (root at 0, padding at 1, sibling pairs in one 64-byte line).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "accel/common/cache_line_allocator.h"
#include "accel/core/aabb.h"

namespace ab {

struct SpherePairTest;

/// One node of bvh-sphere. Interior (count == 0): the children are the sibling pair `offset`, `offset + 1`;
/// leaf (count > 0): primitives [offset, offset + count) of leaf order, as in BvhNode. The sphere contains
/// every primitive below the node exactly (sphere_fit.h rounds the radius up); a NaN centre is the empty
/// sphere (a subtree of primitives without bounds, and the padding node), which no ray enters.
struct alignas(32) SphereNode {
  using PairTest = SpherePairTest;  ///< the ray test of a sibling pair (sphere_entry.h), for walk_bvh2

  float center[3];     ///< centre of the sphere (NaN: empty)
  uint32_t offset;     ///< interior: the children's pair; leaf: the first primitive of leaf order
  float radius;        ///< radius of the sphere
  uint32_t count;      ///< primitives of a leaf, 0 for an interior node
  uint32_t unused[2];  ///< padding to 32 bytes, so that a sibling pair fills one cache line

  /// True for a leaf.
  bool is_leaf() const { return count > 0; }
  /// True for the empty sphere.
  bool empty() const { return std::isnan(center[0]); }
  /// The centre as a vector.
  vec3 centre() const { return {center[0], center[1], center[2]}; }
  /// The sphere's bounding cube (empty for the empty sphere). Its area is 24 r^2, proportional to the
  /// sphere's 4 pi r^2, so the statistics walk's area ratios are the spheres' own.
  AABB cube() const {
    if (empty()) return {};
    return {centre() - vec3(radius), centre() + vec3(radius)};
  }
};
static_assert(sizeof(SphereNode) == 32, "sphere nodes are 32 bytes, as BVH nodes");

/// The NaN that marks an empty sphere.
inline constexpr float kEmptySphere = std::numeric_limits<float>::quiet_NaN();

/// The node array of bvh-sphere.
using SphereNodeArray = std::vector<SphereNode, CacheLineAllocator<SphereNode>>;

}  // namespace ab
