// The tracer's rays as benchmark workloads: exactly the kinds of rays a render of the scene casts.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "datasets/rays.h"
#include "tracer/scene.h"

namespace ab {

/// The tracer's ray kinds for scenes: primary, dof, shadow, glossy, diffuse.
const std::vector<RayKindInfo>& scene_ray_kinds();
/// True when kind names one of scene_ray_kinds().
bool is_scene_ray_kind(const std::string& kind);

/// Closest-hit tracing of a batch (any structure of the project gives the same hits).
using TraceFn = std::function<void(std::span<const Ray>, std::span<Hit>)>;

/// Makes exactly `count` rays of a tracer kind; deterministic in (scene, kind, count, seed).
/// Secondary kinds start at the hits of primary rays (misses are skipped). Throws InputError for an
/// unknown kind, a scene without lights (shadow) or a camera that sees no geometry.
std::vector<Ray> make_scene_rays(const Scene& scene, const TraceFn& trace, const std::string& kind,
                                 uint64_t count, uint64_t seed);

/// Distance by which secondary rays leave a surface, for geometry within `bounds`.
float surface_epsilon(const AABB& bounds);

}  // namespace ab
