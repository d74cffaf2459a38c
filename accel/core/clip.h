// Clipping a convex polygon against planes and boxes: the "perfect split" bounds of the k-d tree
// builders and the exact triangle/box overlap test of the grid and the octree.
#pragma once

#include <array>

#include "accel/core/aabb.h"
#include "accel/core/triangle.h"

namespace ab {

/// A convex polygon with a small fixed capacity (a triangle clipped by a box has at most 9 vertices,
/// clipped by any number of extra planes it can have more; 32 is ample for the uses here).
struct ClipPolygon {
  std::array<vec3, 32> v;
  int n = 0;
};

/// Keeps the part of poly with dot(normal, p) <= offset (Sutherland and Hodgman 1974).
void clip_polygon(ClipPolygon& poly, const vec3& normal, float offset);

/// Keeps the part of poly inside box (six axis planes).
void clip_polygon_to_box(ClipPolygon& poly, const AABB& box);

/// Bounds of the part of tri inside box, intersected with box (so always a subset of it; empty when
/// the triangle misses the box). Wald and Havran 2006 call these the "perfect split" bounds.
AABB clipped_triangle_bounds(const Triangle& tri, const AABB& box);

/// Exact triangle/box overlap (touching counts): true when some point of the triangle lies in the box.
/// Degenerate triangles (segments, points) are handled by the same clipping.
bool triangle_overlaps_box(const Triangle& tri, const AABB& box);

}  // namespace ab
