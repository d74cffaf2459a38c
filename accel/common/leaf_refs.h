// The leaves' primitive references of the spatial structures (k-d trees, octree, BSP tree, the grid's
// cells), in leaf order: ids, and the triangles prepared for the kernel, optionally copied into leaf order
// so that a leaf reads its triangles from one contiguous run (as the BVH's leaves do) instead of gathering
// them by id.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
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

/// How the leaves store their triangles (parameter leaf_copies): on = prepared copies in leaf order; auto =
/// the same when the leaves hold at most kAutoCopyReferences references per triangle (so the copies cost at
/// most 192 bytes per triangle), else one prepared triangle per triangle in id order; off = neither, the
/// kernel on the mesh's triangles by id (the least memory).
enum class LeafCopies { kOff, kOn, kAuto };
/// References per triangle up to which leaf_copies=auto copies.
inline constexpr double kAutoCopyReferences = 3.0;
/// The words of the leaf_copies parameter (for Params::read).
inline const std::map<std::string, LeafCopies> kLeafCopiesWords{
    {"auto", LeafCopies::kAuto}, {"on", LeafCopies::kOn}, {"off", LeafCopies::kOff}};

/// The leaves' primitive references in leaf order: the original ids and, for triangle sets, the triangles
/// prepared for the kernel (PreparedTriangle: terms and edge norms made once, the same bits), copied into
/// leaf order (64 bytes per reference, so a leaf reads its triangles from one contiguous run, as the BVH's
/// leaves do) or once per triangle in id order (64 bytes per triangle, gathered by id), as LeafCopies says.
/// Other primitive sets (instances, moving triangles), and triangles with leaf_copies=off, are reached
/// through their ids and their own kernel.
template <class P>
class LeafRefs {
 public:
  /// True when the primitive set can be prepared (triangles).
  static constexpr bool kCanCopy = std::is_same_v<P, TrianglePrims>;

  /// Takes the leaf-ordered ids and prepares the triangles as `mode` says (in parallel).
  void assign(const P& prims, std::vector<uint32_t> ids, LeafCopies mode) {
    ids_ = std::move(ids);
    tris_.clear();
    copied_ = false;
    if constexpr (kCanCopy) {
      const bool few = double(ids_.size()) <= kAutoCopyReferences * double(prims.size());
      copied_ = mode == LeafCopies::kOn || (mode == LeafCopies::kAuto && few);
      tris_.resize(copied_ ? ids_.size() : mode == LeafCopies::kOff ? 0 : prims.size());
      tbb::parallel_for(tbb::blocked_range<size_t>(0, tris_.size(), size_t(1) << 14), [&](const auto& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
          const uint32_t id = copied_ ? ids_[k] : uint32_t(k);
          tris_[k] = prepare_triangle(prims.triangle(id), id);
        }
      });
    }
  }
  /// The leaf-ordered ids.
  const std::vector<uint32_t>& ids() const { return ids_; }
  /// True when the triangles were copied into leaf order.
  bool copied() const { return copied_; }
  /// Memory of the ids and the prepared triangles.
  size_t bytes() const { return ids_.size() * sizeof(uint32_t) + tris_.size() * sizeof(PreparedTriangle); }

  /// Closest hit over references [first, first + count): the one kernel with the original ray and ids, on a
  /// copy of the ray whose tmax follows best.t (as intersect_id_list: the same hits, and a kernel hit beyond
  /// the best skips the acceptance check).
  template <bool kCount>
  [[gnu::always_inline]] void intersect(const P& prims, uint32_t first, uint32_t count, const Ray& ray,
                                        Hit& best, uint32_t inst, RayCounters& c) const {
    if constexpr (kCanCopy) {
      if (!tris_.empty()) {
        if constexpr (kCount) c.prims += count;
        const float l1_dir = l1_norm(to_lanes(ray.dir));
        Ray r = ray;
        r.tmax = std::min(ray.tmax, best.t);
        for (uint32_t k = first, e = first + count; k < e; ++k) test(r, l1_dir, k, best, inst);
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
    [[maybe_unused]] const float l1_dir = l1_norm(to_lanes(ray.dir));
    Ray r = ray;
    r.tmax = std::min(ray.tmax, best.t);
    for (uint32_t k = first, e = first + count; k < e; ++k) {
      if (mailbox.seen(ids_[k])) {
        if constexpr (kCount) ++c.mailbox_skips;
        continue;
      }
      if constexpr (kCanCopy) {
        if (!tris_.empty()) {
          if constexpr (kCount) ++c.prims;
          test(r, l1_dir, k, best, inst);
          continue;
        }
      }
      if (prims.template intersect<kCount>(ids_[k], r, best, inst, c)) r.tmax = std::min(ray.tmax, best.t);
    }
  }
  /// True when any reference in [first, first + count) that the mailbox has not seen blocks the ray.
  template <bool kCount>
  [[gnu::always_inline]] bool occluded_unseen(const P& prims, uint32_t first, uint32_t count, const Ray& ray,
                                              RayCounters& c, Mailbox& mailbox) const {
    for (uint32_t k = first, e = first + count; k < e; ++k) {
      if (mailbox.seen(ids_[k])) {
        if constexpr (kCount) ++c.mailbox_skips;
      } else if (occluded<kCount>(prims, k, 1, ray, c)) {
        return true;
      }
    }
    return false;
  }
  /// True when any reference in [first, first + count) blocks the ray.
  template <bool kCount>
  [[gnu::always_inline]] bool occluded(const P& prims, uint32_t first, uint32_t count, const Ray& ray,
                                       RayCounters& c) const {
    if constexpr (kCanCopy) {
      if (!tris_.empty()) {
        const float l1_dir = l1_norm(to_lanes(ray.dir));
        for (uint32_t k = first, e = first + count; k < e; ++k) {
          if constexpr (kCount) ++c.prims;
          TriangleHit th;
          if (intersect_prepared(ray, l1_dir, prepared(k), th)) return true;
        }
        return false;
      }
    }
    return occluded_id_list<kCount>(prims, ids_.data() + first, count, ray, c);
  }

 private:
  /// The prepared triangle of reference k.
  [[gnu::always_inline]] const PreparedTriangle& prepared(uint32_t k) const {
    return tris_[copied_ ? k : ids_[k]];
  }
  /// Tests reference k on r (tmax at the best hit) and records a better hit, lowering r.tmax.
  [[gnu::always_inline]] void test(Ray& r, float l1_dir, uint32_t k, Hit& best, uint32_t inst) const {
    const PreparedTriangle& tri = prepared(k);
    TriangleHit th;
    if (intersect_prepared(r, l1_dir, tri, th) && is_better_hit(th.t, inst, tri.id, best)) {
      best = {th.t, tri.id, inst, th.u, th.v};
      r.tmax = std::min(r.tmax, th.t);
    }
  }

  std::vector<uint32_t> ids_;
  bool copied_ = false;
  /// The prepared triangles: not zeroed by resize(), each written once by the parallel fill (its first
  /// touch).
  std::vector<PreparedTriangle, UninitializedAllocator<PreparedTriangle>> tris_;
};

}  // namespace ab
