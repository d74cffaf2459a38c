// The spheres of bvh-sphere, fitted over the binary BVH a builder made (build.h): one sphere per node that
// contains every point of the primitives below it, exactly (the radius is measured in double from the
// float centre and rounded up).
#pragma once

#include <cstdint>
#include <span>

#include "accel/bvh/node.h"
#include "accel/bvh/sphere_node.h"
#include "accel/core/aabb.h"

namespace ab {

/// The points of the primitives in leaf order: primitive k of leaf order owns
/// points[begin[k], begin[k + 1]) (three vertices of a triangle, eight corners of an instance's box, none
/// for a primitive without bounds).
struct LeafOrderPoints {
  std::span<const vec3> points;     ///< every primitive's points, in leaf order
  std::span<const uint32_t> begin;  ///< the first point of each primitive, and the end (size + 1 entries)
};

/// Fits a sphere to every node of `tree` (build_bvh's layout, not empty) and returns the sphere tree with
/// the same topology and leaf ranges. Each node takes the smaller of two spheres that both contain its
/// points: Ritter's (1990, "An efficient bounding sphere") over the node's points, and the smallest sphere
/// around its two children's spheres. Parallel; the same tree for any number of threads.
SphereNodeArray fit_spheres(const BvhNodeArray& tree, const LeafOrderPoints& points);

/// Smallest float radius r such that every point lies within r of centre in exact arithmetic (-1 for no
/// points). Exposed for tests.
float enclosing_radius(const vec3& centre, std::span<const vec3> points);

}  // namespace ab
