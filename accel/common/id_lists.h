// The loops over a list of primitive ids that every spatial tree runs in its leaves (when they hold ids
// only) and over its unbounded primitives: the one kernel of the primitive set, with the original ray.
#pragma once

#include <algorithm>
#include <cstdint>

#include "accel/core/ray.h"
#include "accel/core/stats.h"

namespace ab {

/// Closest hit over a leaf's id list, on a copy of the ray whose tmax follows best.t (the kernel's t, u, v
/// do not depend on tmax, so hits stay identical). Returns true when best changed.
template <bool kCount, class P>
bool intersect_id_list(const P& prims, const uint32_t* ids, uint32_t count, const Ray& ray, Hit& best,
                       uint32_t inst, RayCounters& c) {
  Ray r = ray;
  r.tmax = std::min(ray.tmax, best.t);
  bool changed = false;
  for (uint32_t k = 0; k < count; ++k)
    if (prims.template intersect<kCount>(ids[k], r, best, inst, c)) {
      r.tmax = std::min(ray.tmax, best.t);
      changed = true;
    }
  return changed;
}

/// True when any primitive of a leaf's id list blocks the ray.
template <bool kCount, class P>
bool occluded_id_list(const P& prims, const uint32_t* ids, uint32_t count, const Ray& ray, RayCounters& c) {
  for (uint32_t k = 0; k < count; ++k)
    if (prims.template occluded<kCount>(ids[k], ray, c)) return true;
  return false;
}

}  // namespace ab
