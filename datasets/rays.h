// Ray sets: deterministic workloads made from a mesh (or anything that can be traced).
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "accel/core/aabb.h"

namespace ab {

/// What ray generation needs of the geometry: its bounds, a closest-hit trace (used to find
/// surface points for secondary rays) and the world-space geometric normal at a hit.
struct RayTarget {
  AABB bounds;
  std::function<void(std::span<const Ray>, std::span<Hit>)> trace;
  std::function<vec3(const Hit&)> normal;
};

/// One ray kind.
struct RayKindInfo {
  std::string name;
  std::string description;
};

/// Every ray kind, in listing order.
const std::vector<RayKindInfo>& ray_kinds();

/// Makes exactly `count` rays of `kind`; deterministic in (kind, target geometry, count, seed, views).
/// `views` (primary rays only) splits the rays evenly over that many cameras placed around the bounds;
/// views = 1 is the one default camera. Throws InputError for an unknown kind or a bad `views`.
std::vector<Ray> make_rays(const std::string& kind, const RayTarget& target, uint64_t count, uint64_t seed,
                           uint32_t views = 1);

}  // namespace ab
