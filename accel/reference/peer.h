// What the outside peers (cgal, bullet) share: turning the triangle a peer found into the contract's hit, so
// that their hit files mean what every other hit file means (t in units of the given direction, u and v the
// weights of vertices 1 and 2).
#pragma once

#include <glm/glm.hpp>

#include "accel/core/triangle.h"

namespace ab {

/// The distance along `ray` (in units of its direction) of a point p on it, from the direction's dominant
/// axis (the best conditioned of the three).
double peer_distance(const Ray& ray, const glm::dvec3& p);

/// The barycentric weights (u, v) of vertices 1 and 2 of `tri` at a point p in its plane, in double.
glm::dvec2 peer_barycentrics(const Triangle& tri, const glm::dvec3& p);

/// The contract's hit for triangle `prim` of instance `inst` (vertices `tri`) that a peer reports at point
/// p of the ray: the project's one triangle kernel on the original ray when it hits that triangle, so that
/// t, u and v are the very values brute force computes for it; otherwise the peer's own answer, t from p
/// (clamped to tmin from below: the peer started the ray there) and u, v the weights of p. A miss (prim
/// kInvalidId) when that t lies beyond tmax.
Hit peer_hit(const Ray& ray, const Triangle& tri, uint32_t prim, uint32_t inst, const glm::dvec3& p);

}  // namespace ab
