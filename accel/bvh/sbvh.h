// The spatial-split BVH builder (sbvh.cpp, bvh-sbvh): unlike the other builders it clips primitives, so it
// takes the primitive set's clipped bounds besides the bounds. Its leaf order may hold an id more than once
// (a primitive split between children); every reference of it is tested with the one kernel and the
// original ray, so a duplicate gives the same hit and the acceptance rule keeps the result unchanged.
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "accel/bvh/build.h"
#include "accel/bvh/sbvh_config.h"
#include "accel/core/aabb.h"

namespace ab {

/// The bounds of the part of primitive `id` inside `box` (the primitive set's clipped_bounds).
using ClippedBoundsFn = std::function<AABB(uint32_t id, const AABB& box)>;

/// Binned SAH build with spatial splits (Stich, Friedrich and Dietrich 2009) over the primitives' bounds;
/// at most max(N, ref_budget x N) references. Deterministic: the same tree for any number of threads.
BvhBuildResult build_bvh(const BvhSbvhConfig& config, std::span<const AABB> bounds,
                         const ClippedBoundsFn& clipped_bounds);

}  // namespace ab
