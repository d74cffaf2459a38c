// Instances as a primitive set: the top level of a two-level structure.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/accelerator.h"
#include "accel/core/clip.h"
#include "accel/core/motion.h"

namespace ab {

/// One placement of a base mesh: its structure (shared by every instance of that mesh), the
/// object-to-world transform and its inverse; a moving instance (motion blur) also has its object-to-world
/// transform at the shutter's time steps.
struct Instance {
  std::shared_ptr<const Accelerator> base;
  glm::mat4 to_world{1.0f};
  glm::mat4 to_object{1.0f};
  uint32_t mesh_index = 0;                ///< which base mesh (for reports and flattening)
  std::vector<glm::mat4> to_world_steps;  ///< at the shutter's time steps (empty: does not move)

  /// True when the instance moves during the shutter.
  bool moves() const { return !to_world_steps.empty(); }
};

/// The object-to-world transform of a moving instance at ray time `time`: its time steps interpolated
/// entry by entry (motion.h, as Embree interpolates matrix time steps).
inline glm::mat4 instance_to_world_at(const Instance& inst, float time) {
  return matrix_at(inst.to_world_steps, time);
}
/// The world-to-object transform of a moving instance at ray time `time`: the inverse of
/// instance_to_world_at, the one function that moves a ray into a moving instance.
inline glm::mat4 instance_to_object_at(const Instance& inst, float time) {
  return glm::inverse(instance_to_world_at(inst, time));
}

/// Moves a ray into an instance's object space by the inverse transform, without renormalizing the
/// direction, so that t means the same distance along the ray in both spaces.
inline Ray transform_ray(const Ray& ray, const glm::mat4& to_object) {
  Ray r = ray;
  r.org = vec3(to_object * glm::vec4(ray.org, 1.0f));
  r.dir = vec3(to_object * glm::vec4(ray.dir, 0.0f));
  return r;
}

/// World bounds of box b under transform m (the bounds of its eight transformed corners).
inline AABB transform_bounds(const AABB& b, const glm::mat4& m) {
  AABB out;
  if (b.empty()) return out;
  for (int c = 0; c < 8; ++c) {
    const vec3 p((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z);
    out.extend(vec3(m * glm::vec4(p, 1.0f)));
  }
  return out;
}

/// The growth of a moving instance's boxes over the shutter (`swept`, their union): 2^-12 of its size and
/// magnitude, for the rounding of the interpolated matrix and its inverse.
inline vec3 instance_motion_margin(const AABB& swept) {
  return (swept.extent() + glm::max(glm::abs(swept.lo), glm::abs(swept.hi))) * 0x1p-12f;
}

/// World bounds of an instance over the shutter. A static instance: its base's box transformed. A moving
/// one: the union of that box under every time step's matrix (a point moves along M(f) p = (1 - f) M_k p +
/// f M_k+1 p within a segment, so this union is exact for the interpolation of matrix_at, rotations
/// included), grown by instance_motion_margin.
inline AABB instance_world_bounds(const Instance& inst) {
  if (!inst.moves()) return transform_bounds(inst.base->bounds(), inst.to_world);
  AABB out;
  for (const glm::mat4& m : inst.to_world_steps) out.extend(transform_bounds(inst.base->bounds(), m));
  if (out.empty()) return out;
  const vec3 margin = instance_motion_margin(out);
  return {out.lo - margin, out.hi + margin};
}

/// World bounds of a moving instance at its time step k, grown as instance_world_bounds grows (the motion
/// BVH interpolates these boxes between the steps).
inline AABB instance_step_bounds(const Instance& inst, size_t k) {
  const AABB world = instance_world_bounds(inst);
  const AABB b = transform_bounds(inst.base->bounds(), inst.to_world_steps[k]);
  if (b.empty()) return b;
  const vec3 margin = instance_motion_margin(world);
  return {b.lo - margin, b.hi + margin};
}

/// The instances of a scene; primitive i is instance i (its index in document order).
class InstancePrims {
 public:
  /// Takes the instances; their base structures must already be built.
  explicit InstancePrims(std::vector<Instance> instances) : instances_(std::move(instances)) {
    world_.reserve(instances_.size());
    for (const Instance& inst : instances_) {
      world_.push_back(instance_world_bounds(inst));
      bounds_.extend(world_.back());
    }
  }

  /// Number of instances.
  size_t size() const { return instances_.size(); }
  /// Instance i.
  const Instance& instance(size_t i) const { return instances_[i]; }
  /// World bounds of instance i.
  AABB bounds(size_t i) const { return world_[i]; }
  /// Bounds of every instance.
  AABB bounds() const { return bounds_; }
  /// Centre of instance i's world bounds.
  vec3 centroid(size_t i) const { return world_[i].center(); }
  /// Instance bounds clipped to box (conservative: the instance's world box is not tight).
  AABB clipped_bounds(size_t i, const AABB& box) const { return AABB::intersection(world_[i], box); }
  /// Conservative overlap: the world boxes overlap.
  bool overlaps(size_t i, const AABB& box) const { return world_[i].overlaps(box); }

  /// Traces the ray through instance i's base structure in object space; hits carry inst = i.
  template <bool kCount>
  bool intersect(size_t i, const Ray& ray, Hit& best, uint32_t /*inst*/, RayCounters& c) const {
    if constexpr (kCount) ++c.prims;
    const Hit before = best;
    instances_[i].base->intersect_one(object_ray(i, ray), best, static_cast<uint32_t>(i),
                                      kCount ? &c : nullptr);
    return best.t != before.t || best.prim != before.prim || best.inst != before.inst;
  }
  /// True when instance i blocks the ray within [tmin, tmax].
  template <bool kCount>
  bool occluded(size_t i, const Ray& ray, RayCounters& c) const {
    if constexpr (kCount) ++c.prims;
    return instances_[i].base->occluded_one(object_ray(i, ray), kCount ? &c : nullptr);
  }

 private:
  /// The ray in instance i's object space (at the ray's time when the instance moves).
  Ray object_ray(size_t i, const Ray& ray) const {
    const Instance& inst = instances_[i];
    if (!inst.moves()) return transform_ray(ray, inst.to_object);
    return transform_ray(ray, instance_to_object_at(inst, ray.time));
  }

  std::vector<Instance> instances_;
  std::vector<AABB> world_;
  AABB bounds_;
};

}  // namespace ab
