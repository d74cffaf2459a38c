// The closest-hit and any-hit queries of every spatial tree (k-d trees, octree, BSP tree), written once
// over the tree's own front-to-back walk.
#pragma once

#include <cstdint>

#include "accel/common/id_lists.h"
#include "accel/core/accelerator.h"

namespace ab {

/// The closest-hit and any-hit queries of a spatial tree D: the unbounded primitives by list
/// (finite_primitives.h), then D's front-to-back traverse<kCount>(ray, c, leaf(first, count), best_t())
/// over the leaves' references (LeafRefs). D declares this class a friend for prims_, unbounded_, leaves_
/// and traverse.
template <class D>
class SpatialTreeQueries : public AcceleratorBase<D> {
 public:
  /// Closest hit, front to back; a leaf's cells are pruned by best.t.
  template <bool kCount>
  [[gnu::flatten]] void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    const D& d = static_cast<const D&>(*this);
    if (!d.unbounded_.empty())
      intersect_id_list<kCount>(*d.prims_, d.unbounded_.data(), uint32_t(d.unbounded_.size()), ray, best,
                                inst, c);
    d.template traverse<kCount>(
        ray, c,
        [&](uint32_t first, uint32_t count) {
          d.leaves_.template intersect<kCount>(*d.prims_, first, count, ray, best, inst, c);
          return false;
        },
        [&] { return best.t; });
  }

  /// Any hit: the same walk, stopping at the first primitive that blocks the ray.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    const D& d = static_cast<const D&>(*this);
    if (occluded_id_list<kCount>(*d.prims_, d.unbounded_.data(), uint32_t(d.unbounded_.size()), ray, c))
      return true;
    return d.template traverse<kCount>(
        ray, c,
        [&](uint32_t first, uint32_t count) {
          return d.leaves_.template occluded<kCount>(*d.prims_, first, count, ray, c);
        },
        [] { return kInf; });
  }
};

}  // namespace ab
