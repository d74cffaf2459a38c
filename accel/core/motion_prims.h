// A deforming triangle mesh as a primitive set: the vertex positions at T >= 2 time steps over the shutter
// (the same triangle list at each), interpolated linearly per segment at the ray's time (motion.h).
// Builders see each moving triangle's swept box, the union of its boxes at the time steps, which is exact
// for per-segment linear motion; triangles that do not move keep their exact box and overlap tests.
#pragma once

#include <memory>
#include <stdexcept>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/clip.h"
#include "accel/core/mesh.h"
#include "accel/core/motion.h"
#include "accel/core/ray.h"
#include "accel/core/stats.h"
#include "accel/core/triangle.h"

namespace ab {

/// The triangles of a mesh at every time step of the shutter; triangle i at time t is triangle_at(i, t).
class MotionTrianglePrims {
 public:
  /// The mesh at each of steps.size() >= 2 time steps; every step has step 0's triangle list (throws
  /// std::invalid_argument otherwise: the caller checks its input).
  explicit MotionTrianglePrims(std::vector<std::shared_ptr<const Mesh>> steps);

  /// Number of triangles.
  size_t size() const { return moves_.size(); }
  /// Number of time steps.
  uint32_t steps() const { return steps_; }
  /// The mesh at time step 0 (triangle lists and reports).
  const Mesh& mesh() const { return *meshes_.front(); }
  /// True when triangle i moves during the shutter.
  bool moves(size_t i) const { return moves_[i] != 0; }
  /// Triangle i at time step k.
  const Triangle& triangle_step(size_t i, uint32_t k) const { return tris_[i * steps_ + k]; }

  /// Triangle i at time (in [0, 1]): the one interpolation every structure uses (a triangle that does not
  /// move is its step-0 triangle exactly).
  Triangle triangle_at(size_t i, float time) const {
    const Triangle* t = &tris_[i * steps_];
    if (!moves_[i]) return t[0];
    const MotionSegment seg = motion_segment(time, steps_);
    return lerp_triangle(t[seg.index], t[seg.index + 1], seg.fraction);
  }

  /// Swept bounds of triangle i (the union of its boxes at the time steps).
  AABB bounds(size_t i) const { return swept_[i]; }
  /// Bounds of everything over the shutter.
  AABB bounds() const { return bounds_; }
  /// Centre of the swept bounds of triangle i.
  vec3 centroid(size_t i) const { return swept_[i].center(); }
  /// The part of triangle i's swept box inside box (a moving triangle), or its perfect-split bounds.
  AABB clipped_bounds(size_t i, const AABB& box) const {
    if (moves_[i]) return AABB::intersection(swept_[i], box);
    return clipped_triangle_bounds(tris_[i * steps_], box);
  }
  /// Conservative overlap: the swept box overlaps box (a moving triangle), or the exact test.
  bool overlaps(size_t i, const AABB& box) const {
    if (moves_[i]) return swept_[i].overlaps(box);
    return triangle_overlaps_box(tris_[i * steps_], box);
  }

  /// Tests triangle i at the ray's time and keeps it in best when better; ids as (inst, i).
  template <bool kCount>
  bool intersect(size_t i, const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if constexpr (kCount) ++c.prims;
    return intersect_and_update(ray, triangle_at(i, ray.time), static_cast<uint32_t>(i), inst, best);
  }
  /// True when triangle i at the ray's time is hit within [tmin, tmax].
  template <bool kCount>
  bool occluded(size_t i, const Ray& ray, RayCounters& c) const {
    if constexpr (kCount) ++c.prims;
    TriangleHit th;
    return intersect_triangle(ray, triangle_at(i, ray.time), th);
  }

 private:
  std::vector<std::shared_ptr<const Mesh>> meshes_;
  uint32_t steps_ = 0;
  std::vector<Triangle> tris_;  ///< triangle i's steps at [i steps_, (i + 1) steps_)
  std::vector<uint8_t> moves_;
  std::vector<AABB> swept_;
  AABB bounds_;
};

}  // namespace ab
