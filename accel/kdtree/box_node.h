// A k-d tree node under construction as its primitives' clipped boxes (the perfect-split bounds of Wald
// and Havran 2006: each primitive's bounds clipped to the node box), and the one partition of such a node
// into its two children, shared by the median builder and the binned top levels of the SAH builder: the
// builder's side rule classifies every box, straddling primitives are clipped into each child box grown by
// the insertion margin (clip_into_child), and both lists keep the node's order. Classification and
// clipping run in parallel over the primitives; the lists are the same for any thread count.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cstdint>
#include <vector>

#include "accel/common/conservative_insertion.h"
#include "accel/core/aabb.h"

namespace ab {

/// A node as its box, primitive ids and their boxes clipped to the node.
struct KdBoxNode {
  AABB box;                   ///< the node's box
  std::vector<uint32_t> ids;  ///< its primitives
  std::vector<AABB> bounds;   ///< per primitive, its bounds clipped to the box (the perfect splits)
};

/// The boxes below and above the plane `split` on axis a of a node box.
inline void child_boxes(const AABB& box, int a, float split, AABB& below, AABB& above) {
  below = box;
  above = box;
  below.hi[a] = split;
  above.lo[a] = split;
}

/// Calls body(begin, end) over [0, n): at once when n is at most `grain` (a small node pays no task), else
/// in parallel chunks of `grain`.
template <class Body>
void for_chunks(size_t n, size_t grain, Body&& body) {
  if (n <= grain) return body(size_t(0), n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain),
                    [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
}

/// The root over ids inside box: every primitive with its bounds clipped to the box (in parallel).
template <class P>
KdBoxNode make_box_root(const P& prims, const std::vector<uint32_t>& ids, const AABB& box) {
  KdBoxNode root{box, ids, std::vector<AABB>(ids.size())};
  tbb::parallel_for(size_t(0), ids.size(),
                    [&](size_t i) { root.bounds[i] = prims.clipped_bounds(ids[i], box); });
  return root;
}

/// Splits node at `split` on axis a into left and right: side(clipped box) gives each primitive's sides (bit
/// 0 left, bit 1 right); a primitive on both is clipped into each child box with `margin`, the others
/// keep their boxes.
template <class P, class Side>
void partition_box_node(const P& prims, const KdBoxNode& node, int a, float split, float margin, Side&& side,
                        KdBoxNode& left, KdBoxNode& right) {
  const size_t n = node.ids.size();
  child_boxes(node.box, a, split, left.box, right.box);
  // Not thread-local scratch: a thread waiting for the chunks may run another node's partition meanwhile.
  std::vector<uint8_t> sides(n);
  uint8_t* const sd = sides.data();
  for_chunks(n, 4096, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) sd[i] = side(node.bounds[i]);
  });
  size_t nl = 0, nr = 0;
  for (size_t i = 0; i < n; ++i) nl += sd[i] & 1, nr += sd[i] >> 1;
  left.ids.reserve(nl), left.bounds.reserve(nl), right.ids.reserve(nr), right.bounds.reserve(nr);
  std::vector<std::array<uint32_t, 3>> both;  // node index, left index, right index
  both.reserve(nl + nr - n);
  for (size_t i = 0; i < n; ++i) {
    if (sd[i] == 3) both.push_back({uint32_t(i), uint32_t(left.ids.size()), uint32_t(right.ids.size())});
    if (sd[i] & 1) left.ids.push_back(node.ids[i]), left.bounds.push_back(node.bounds[i]);
    if (sd[i] & 2) right.ids.push_back(node.ids[i]), right.bounds.push_back(node.bounds[i]);
  }
  for_chunks(both.size(), 256, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      const auto [i, li, ri] = both[k];
      left.bounds[li] = clip_into_child(prims, node.ids[i], left.box, margin);
      right.bounds[ri] = clip_into_child(prims, node.ids[i], right.box, margin);
    }
  });
}

}  // namespace ab
