// Primitive sets: what a builder sees of its input. A structure is a template over the primitive set,
// so the same code serves as a bottom level (over triangles) and a top level (over instances).
//
// A primitive set P provides:
//   size_t size() const;
//   AABB bounds(size_t i) const;                          // world (or object-space) bounds of primitive i
//   vec3 centroid(size_t i) const;                        // centre used by object-partitioning builders
//   AABB clipped_bounds(size_t i, const AABB& box) const; // bounds of the part of i inside box (empty: none)
//   bool overlaps(size_t i, const AABB& box) const;       // exact overlap (touching counts)
//   template <bool kCount>
//   bool intersect(size_t i, const Ray&, Hit& best, uint32_t inst, RayCounters&) const;
//   template <bool kCount>
//   bool occluded(size_t i, const Ray&, RayCounters&) const;
//   AABB bounds() const;                                  // bounds of everything
// intersect() applies the one acceptance rule (is_better_hit) and returns true when best changed.
#pragma once

#include <memory>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/clip.h"
#include "accel/core/mesh.h"
#include "accel/core/stats.h"
#include "accel/core/triangle.h"

namespace ab {

/// The triangles of a mesh, with their vertices copied out in id order for fast access.
class TrianglePrims {
 public:
  /// Copies the triangles of mesh (which is kept alive for adapters that need the indexed form), in
  /// parallel (a BVH refitted from a frame's mesh makes none: refit.h); the same result on any thread count.
  explicit TrianglePrims(std::shared_ptr<const Mesh> mesh);

  /// Number of triangles.
  size_t size() const { return tris_.size(); }
  /// Triangle i.
  const Triangle& triangle(size_t i) const { return tris_[i]; }
  /// All triangles in id order.
  const std::vector<Triangle>& triangles() const { return tris_; }
  /// The source mesh.
  const Mesh& mesh() const { return *mesh_; }
  /// Bounds of triangle i.
  AABB bounds(size_t i) const { return tris_[i].bounds(); }
  /// Bounds of every triangle.
  AABB bounds() const { return bounds_; }
  /// Centre of the bounds of triangle i.
  vec3 centroid(size_t i) const { return tris_[i].bounds().center(); }
  /// Perfect-split bounds of triangle i inside box.
  AABB clipped_bounds(size_t i, const AABB& box) const { return clipped_triangle_bounds(tris_[i], box); }
  /// Exact triangle/box overlap.
  bool overlaps(size_t i, const AABB& box) const { return triangle_overlaps_box(tris_[i], box); }

  /// Tests triangle i and keeps it in best when better; ids as (inst, i).
  template <bool kCount>
  bool intersect(size_t i, const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if constexpr (kCount) ++c.prims;
    return intersect_and_update(ray, tris_[i], static_cast<uint32_t>(i), inst, best);
  }
  /// True when triangle i is hit within [tmin, tmax].
  template <bool kCount>
  bool occluded(size_t i, const Ray& ray, RayCounters& c) const {
    if constexpr (kCount) ++c.prims;
    TriangleHit th;
    return intersect_triangle(ray, tris_[i], th);
  }

 private:
  std::shared_ptr<const Mesh> mesh_;
  std::vector<Triangle> tris_;
  AABB bounds_;
};

}  // namespace ab
