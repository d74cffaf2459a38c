// The exact plane sweep of the SAH k-d tree (Wald and Havran 2006, "On building fast kd-trees for ray
// tracing, and on doing that in O(N log N)", algorithm 4): a node's start, end and planar events per axis,
// sorted, and one linear sweep over them that prices every plane with the cost model (SahCosts, sah.h),
// both placements of the planar primitives, and keeps the cheapest plane and the cheapest one with
// progress. The binned planes of large nodes (sah_bins.h) price their candidates with the same
// evaluate_kd_plane.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "accel/common/sah.h"
#include "accel/core/aabb.h"
#include "accel/core/ray.h"

namespace ab {

/// A sweep event: position along one axis and (primitive's index in its node << 2 | type).
struct KdEvent {
  float pos;     ///< position along the axis
  uint32_t key;  ///< local index << 2 | type

  /// Event types, in the order the sweep needs at one position: ends, planars, starts.
  enum Type : uint32_t { kEnd = 0, kPlanar = 1, kStart = 2 };
  /// Index of the primitive in its node.
  uint32_t local() const { return key >> 2; }
  /// The event's type.
  uint32_t type() const { return key & 3u; }
  /// Total order: position, then type, then primitive (so any sort gives the same list).
  bool operator<(const KdEvent& o) const {
    if (pos != o.pos) return pos < o.pos;
    const uint32_t ta = type(), tb = o.type();
    return ta != tb ? ta < tb : key < o.key;
  }
};

/// A node under construction: box, primitive ids and the sorted events of each axis.
struct KdEventNode {
  AABB box;                                    ///< the node's box
  std::vector<uint32_t> ids;                   ///< its primitives
  std::array<std::vector<KdEvent>, 3> events;  ///< per axis, sorted
};

/// Appends the events of a primitive with clipped bounds cb as local index `local`.
inline void add_kd_events(const AABB& cb, uint32_t local, std::array<std::vector<KdEvent>, 3>& ev) {
  for (int a = 0; a < 3; ++a) {
    if (cb.lo[a] == cb.hi[a]) {
      ev[a].push_back({cb.lo[a], (local << 2) | KdEvent::kPlanar});
    } else {
      ev[a].push_back({cb.lo[a], (local << 2) | KdEvent::kStart});
      ev[a].push_back({cb.hi[a], (local << 2) | KdEvent::kEnd});
    }
  }
}

/// Result of the sweep.
struct KdSahPlane {
  int axis = -1;                     ///< -1: no plane inside the box
  float pos = 0.0f;                  ///< plane position
  float cost = kInf;                 ///< its SAH cost
  bool planar_left = true;           ///< planar primitives at pos are counted on the left
  uint32_t n_left = 0, n_right = 0;  ///< primitives on each side
};

/// Area terms of the children of a node box along one axis, so that each plane costs a few flops. They
/// are made in the node's area_frame (sah.h), so the ratios are the same at any scale.
struct KdAxisAreas {
  float lo, hi, frame, cap, side, inv_area;  ///< child area = (cap + side * length * frame) * inv_area

  /// Terms of box along axis a.
  KdAxisAreas(const AABB& box, int a) : lo(box.lo[a]), hi(box.hi[a]) {
    const vec3 own = box.extent();
    frame = area_frame(own);
    const vec3 e = own * frame;
    const float e1 = e[(a + 1) % 3], e2 = e[(a + 2) % 3];
    cap = 2.0f * e1 * e2;
    side = 2.0f * (e1 + e2);
    inv_area = 1.0f / area_of_extent(e);
  }
  /// The share of the node's area of the child whose extent along the axis is `length`.
  float share(float length) const { return (cap + side * (length * frame)) * inv_area; }
};

/// The cheapest plane of a node, and the cheapest one that leaves fewer than all n primitives on each side
/// (the plane of a max_leaf split, which must make progress).
struct KdSahChoice {
  KdSahPlane best;      ///< cheapest plane
  KdSahPlane progress;  ///< cheapest plane with both sides smaller than the node
};

/// Keeps plane (a, pos, cost c, planar side, counts) in best when cheaper.
inline void keep_cheaper(KdSahPlane& best, int a, float pos, float c, bool planar_left, uint32_t nl,
                         uint32_t nr) {
  if (c < best.cost) best = {a, pos, c, planar_left, nl, nr};
}

/// Evaluates plane `pos` on axis a with the paper's counts, both placements of planar primitives. The
/// areas are relative to the node's (the probabilities P_L, P_R), so the cost model is called with a
/// parent area of 1. Without planar primitives counted (np 0), planar_left is the side any planar
/// primitive at the plane is put on (the binned planes at the geometry's lower extent put them right).
inline void evaluate_kd_plane(const SahCosts& costs, const KdAxisAreas& ar, int a, float pos, uint32_t nl,
                              uint32_t np, uint32_t nr, uint32_t n, KdSahChoice& choice,
                              bool planar_left = true) {
  const float pl = ar.share(pos - ar.lo);
  const float pr = ar.share(ar.hi - pos);
  const float cl = costs.split(1.0f, pl, nl + np, pr, nr);
  const float cr = np ? costs.split(1.0f, pl, nl, pr, nr + np) : cl;
  const bool left = np ? cl <= cr : planar_left;
  keep_cheaper(choice.best, a, pos, std::min(cl, cr), left, left ? nl + np : nl, left ? nr : nr + np);
  if (nl + np < n && nr < n) keep_cheaper(choice.progress, a, pos, cl, true, nl + np, nr);
  if (np && nl < n && nr + np < n) keep_cheaper(choice.progress, a, pos, cr, false, nl, nr + np);
}

/// Finds the cheapest plane strictly inside the node box by one sweep per axis (Wald and Havran 2006,
/// algorithm 4).
inline KdSahChoice find_kd_sah_plane(const SahCosts& costs, const KdEventNode& node) {
  KdSahChoice best;
  if (!(frame_area(node.box) > 0.0f)) return best;
  const uint32_t n = uint32_t(node.ids.size());
  for (int a = 0; a < 3; ++a) {
    const std::vector<KdEvent>& ev = node.events[a];
    const KdAxisAreas ar(node.box, a);
    uint32_t nl = 0, nr = n;
    for (size_t i = 0; i < ev.size();) {
      const float p = ev[i].pos;
      uint32_t ends = 0, planars = 0, starts = 0;
      for (; i < ev.size() && ev[i].pos == p && ev[i].type() == KdEvent::kEnd; ++i) ++ends;
      for (; i < ev.size() && ev[i].pos == p && ev[i].type() == KdEvent::kPlanar; ++i) ++planars;
      for (; i < ev.size() && ev[i].pos == p && ev[i].type() == KdEvent::kStart; ++i) ++starts;
      nr -= planars + ends;
      if (p > node.box.lo[a] && p < node.box.hi[a])
        evaluate_kd_plane(costs, ar, a, p, nl, planars, nr, n, best);
      nl += starts + planars;
    }
  }
  return best;
}

}  // namespace ab
