// The interface of the BVH builders: one function per method, chosen by the type of its Config (object
// median in median.cpp, binned SAH in binned.cpp, full-sweep SAH in sweep.cpp), and what each returns. The
// builders need no primitive set, only the primitives' bounds and centroids, so they are not templates.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "accel/bvh/config.h"
#include "accel/bvh/node.h"
#include "accel/core/aabb.h"

namespace ab {

/// What a builder produces: the binary node array (root at 0, padding at 1, sibling pairs in depth-first
/// order) and the leaf order of the primitive ids. Its statistics come from the one statistics walk.
struct BvhBuildResult {
  BvhNodeArray nodes;           ///< empty for no primitives
  std::vector<uint32_t> order;  ///< order[k]: id of the k-th primitive in leaf order
};

/// Object-median build (median.cpp). Deterministic: the same tree for any number of threads, as every
/// builder below.
BvhBuildResult build_bvh(const BvhMedianConfig& config, std::span<const AABB> bounds,
                         std::span<const vec3> centroids);

/// Binned SAH build (binned.cpp). It bins the centres of the bounds, which is what both primitive sets'
/// centroid() returns, so `centroids` is not read.
BvhBuildResult build_bvh(const BvhSahConfig& config, std::span<const AABB> bounds,
                         std::span<const vec3> centroids);

/// Full-sweep SAH build (sweep.cpp).
BvhBuildResult build_bvh(const BvhSweepConfig& config, std::span<const AABB> bounds,
                         std::span<const vec3> centroids);

}  // namespace ab
