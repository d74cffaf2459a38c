// The leaves' primitive references of the spatial trees (k-d trees, octree, BSP tree), in leaf order: ids,
// and optionally a copy of each referenced triangle so that a leaf reads its triangles from one contiguous
// run (as the BVH's leaves do) instead of gathering them by id.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "accel/common/cache_line_allocator.h"
#include "accel/common/id_lists.h"
#include "accel/common/mailbox.h"
#include "accel/core/primitives.h"
#include "accel/core/triangle.h"

namespace ab {

/// When the leaves copy their triangles (parameter leaf_copies: on, off, or auto = when the leaves hold at
/// most kAutoCopyReferences references per triangle, so the copies cost at most about 108 bytes per
/// triangle).
enum class LeafCopies { kOff, kOn, kAuto };
/// References per triangle up to which leaf_copies=auto copies.
inline constexpr double kAutoCopyReferences = 3.0;
/// The words of the leaf_copies parameter (for Params::read).
inline const std::map<std::string, LeafCopies> kLeafCopiesWords{
    {"auto", LeafCopies::kAuto}, {"on", LeafCopies::kOn}, {"off", LeafCopies::kOff}};

/// The leaves' primitive references in leaf order: the original ids and, for triangle sets when asked, a
/// copy of each referenced triangle in the same order. A triangle referenced by several leaves is copied
/// once per reference (36 bytes each), which is why it is optional. Other primitive sets (instances) are
/// always reached through their ids.
template <class P>
class LeafRefs {
 public:
  /// True when the primitive set can be copied into leaf order.
  static constexpr bool kCanCopy = std::is_same_v<P, TrianglePrims>;

  /// Takes the leaf-ordered ids and copies the triangles they name as `mode` says (in parallel).
  void assign(const P& prims, std::vector<uint32_t> ids, LeafCopies mode) {
    ids_ = std::move(ids);
    tris_.clear();
    if constexpr (kCanCopy) {
      const bool few = double(ids_.size()) <= kAutoCopyReferences * double(prims.size());
      if (mode == LeafCopies::kOn || (mode == LeafCopies::kAuto && few)) {
        tris_.resize(ids_.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, ids_.size(), size_t(1) << 14), [&](const auto& r) {
          for (size_t k = r.begin(); k < r.end(); ++k) tris_[k] = prims.triangle(ids_[k]);
        });
      }
    }
  }
  /// The leaf-ordered ids.
  const std::vector<uint32_t>& ids() const { return ids_; }
  /// True when the triangles were copied.
  bool copied() const { return !tris_.empty(); }
  /// Memory of the ids and copies.
  size_t bytes() const { return ids_.size() * sizeof(uint32_t) + tris_.size() * sizeof(Triangle); }

  /// Closest hit over references [first, first + count): the one kernel with the original ray and ids.
  template <bool kCount>
  [[gnu::always_inline]] void intersect(const P& prims, uint32_t first, uint32_t count, const Ray& ray,
                                        Hit& best, uint32_t inst, RayCounters& c) const {
    if constexpr (kCanCopy) {
      if (!tris_.empty()) {
        if constexpr (kCount) c.prims += count;
        for (uint32_t k = first, e = first + count; k < e; ++k) {
          TriangleHit th;  // the id (another array) is read only for a hit
          if (intersect_triangle(ray, tris_[k], th) && is_better_hit(th.t, inst, ids_[k], best))
            best = {th.t, ids_[k], inst, th.u, th.v};
        }
        return;
      }
    }
    intersect_id_list<kCount>(prims, ids_.data() + first, count, ray, best, inst, c);
  }
  /// Closest hit over the references [first, first + count) that the mailbox has not seen for this ray:
  /// the same kernel, each primitive tested once however many of the ray's leaves reference it (a
  /// primitive already tested cannot win later, as the best hit only gets closer).
  template <bool kCount>
  [[gnu::always_inline]] void intersect_unseen(const P& prims, uint32_t first, uint32_t count, const Ray& ray,
                                               Hit& best, uint32_t inst, RayCounters& c,
                                               Mailbox& mailbox) const {
    for (uint32_t k = first, e = first + count; k < e; ++k) {
      if (mailbox.seen(ids_[k])) {
        if constexpr (kCount) ++c.mailbox_skips;
        continue;
      }
      if constexpr (kCanCopy) {
        if (!tris_.empty()) {
          if constexpr (kCount) ++c.prims;
          TriangleHit th;
          if (intersect_triangle(ray, tris_[k], th) && is_better_hit(th.t, inst, ids_[k], best))
            best = {th.t, ids_[k], inst, th.u, th.v};
          continue;
        }
      }
      intersect_id_list<kCount>(prims, &ids_[k], 1, ray, best, inst, c);
    }
  }
  /// True when any reference in [first, first + count) blocks the ray.
  template <bool kCount>
  [[gnu::always_inline]] bool occluded(const P& prims, uint32_t first, uint32_t count, const Ray& ray,
                                       RayCounters& c) const {
    if constexpr (kCanCopy) {
      if (!tris_.empty()) {
        for (uint32_t k = first, e = first + count; k < e; ++k) {
          if constexpr (kCount) ++c.prims;
          TriangleHit th;
          if (intersect_triangle(ray, tris_[k], th)) return true;
        }
        return false;
      }
    }
    return occluded_id_list<kCount>(prims, ids_.data() + first, count, ray, c);
  }

 private:
  std::vector<uint32_t> ids_;
  /// The copies: not zeroed by resize(), each written once by the parallel copy (its first touch).
  std::vector<Triangle, UninitializedAllocator<Triangle>> tris_;
};

}  // namespace ab
