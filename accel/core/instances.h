// Instances as a primitive set: the top level of a two-level structure.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/accelerator.h"
#include "accel/core/clip.h"

namespace ab {

/// One placement of a base mesh: its structure (shared by every instance of that mesh), the
/// object-to-world transform and its inverse.
struct Instance {
  std::shared_ptr<const Accelerator> base;
  glm::mat4 to_world{1.0f};
  glm::mat4 to_object{1.0f};
  uint32_t mesh_index = 0;  ///< which base mesh (for reports and flattening)
};

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

/// The instances of a scene; primitive i is instance i (its index in document order).
class InstancePrims {
 public:
  /// Takes the instances; their base structures must already be built.
  explicit InstancePrims(std::vector<Instance> instances) : instances_(std::move(instances)) {
    world_.reserve(instances_.size());
    for (const Instance& inst : instances_) {
      world_.push_back(transform_bounds(inst.base->bounds(), inst.to_world));
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
    instances_[i].base->intersect_one(transform_ray(ray, instances_[i].to_object), best,
                                      static_cast<uint32_t>(i), kCount ? &c : nullptr);
    return best.t != before.t || best.prim != before.prim || best.inst != before.inst;
  }
  /// True when instance i blocks the ray within [tmin, tmax].
  template <bool kCount>
  bool occluded(size_t i, const Ray& ray, RayCounters& c) const {
    if constexpr (kCount) ++c.prims;
    return instances_[i].base->occluded_one(transform_ray(ray, instances_[i].to_object),
                                            kCount ? &c : nullptr);
  }

 private:
  std::vector<Instance> instances_;
  std::vector<AABB> world_;
  AABB bounds_;
};

}  // namespace ab
