// The traditional k-d tree build (Bentley 1975; the spatial-median k-d tree of the ray-tracing lectures):
// each node splits at the median of its primitives' centres along its longest axis (or the axes in turn),
// until a leaf holds at most leaf_size primitives, the depth limit is reached, or more than straddle_limit
// of them would straddle the plane (then splitting mostly duplicates them). Primitives are tracked by
// their perfect-split bounds inside the node box, and the partition is conservative: a primitive that
// touches the plane or comes within the insertion margin of it goes to both children.
#pragma once

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <vector>

#include "accel/common/conservative_insertion.h"
#include "accel/kdtree/config.h"
#include "accel/kdtree/node.h"

namespace ab {

/// Builds median-split k-d trees over a primitive set P.
template <class P>
class KdMedianBuilder {
 public:
  /// A primitive in a node: its id and its bounds clipped to the node box.
  struct Ref {
    uint32_t id;  ///< primitive id
    AABB cb;      ///< its bounds clipped to the node box
  };

  /// Builder over prims with the tree's configuration and its resolved depth limit (> 0).
  KdMedianBuilder(const P& prims, const KdMedianConfig& config, int depth_limit)
      : prims_(prims), config_(config), depth_limit_(depth_limit) {}

  /// Builds the tree over the primitives ids (finite bounds) inside box into out.
  void build(const std::vector<uint32_t>& ids, const AABB& box, KdBuffer& out) const {
    std::vector<Ref> refs(ids.size());
    for (size_t i = 0; i < ids.size(); ++i) refs[i] = {ids[i], prims_.clipped_bounds(ids[i], box)};
    build_node(std::move(refs), box, 0, out);
  }

 private:
  void build_node(std::vector<Ref>&& refs, const AABB& box, int depth, KdBuffer& out) const {
    const size_t n = refs.size();
    int axis = config_.axis == KdAxisRule::kCycle ? depth % 3 : box.longest_axis();
    float split = 0.0f;
    if (n <= config_.leaf_size || depth >= depth_limit_ || !median_plane(refs, box, axis, split)) {
      make_leaf(refs, out);
      return;
    }
    std::vector<Ref> left, right;
    AABB lbox = box, rbox = box;
    lbox.hi[axis] = split;
    rbox.lo[axis] = split;
    partition(refs, axis, split, insertion_margin(box), lbox, rbox, left, right);
    if (double(left.size() + right.size()) > double(n) * (1.0 + config_.straddle_limit)) {  // no longer pays
      make_leaf(refs, out);
      return;
    }
    std::vector<Ref>().swap(refs);
    const size_t self = out.nodes.size();
    out.nodes.push_back(KdNode::leaf(0, 0));
    if (n >= kParallelMin) {
      KdBuffer lb, rb;
      tbb::parallel_invoke([&] { build_node(std::move(left), lbox, depth + 1, lb); },
                           [&] { build_node(std::move(right), rbox, depth + 1, rb); });
      out.append(lb);
      out.nodes[self] = KdNode::interior(axis, split, uint32_t(out.nodes.size()));
      out.append(rb);
    } else {
      build_node(std::move(left), lbox, depth + 1, out);
      out.nodes[self] = KdNode::interior(axis, split, uint32_t(out.nodes.size()));
      build_node(std::move(right), rbox, depth + 1, out);
    }
  }

  /// Median of the clipped centres along axis; false when it does not lie strictly inside the box.
  static bool median_plane(const std::vector<Ref>& refs, const AABB& box, int axis, float& split) {
    std::vector<float> c(refs.size());
    for (size_t i = 0; i < refs.size(); ++i) c[i] = 0.5f * (refs[i].cb.lo[axis] + refs[i].cb.hi[axis]);
    auto mid = c.begin() + c.size() / 2;
    std::nth_element(c.begin(), mid, c.end());
    split = *mid;
    return split > box.lo[axis] && split < box.hi[axis];
  }

  void partition(const std::vector<Ref>& refs, int axis, float split, float margin, const AABB& lbox,
                 const AABB& rbox, std::vector<Ref>& left, std::vector<Ref>& right) const {
    for (const Ref& r : refs) {
      const bool to_left = r.cb.lo[axis] <= split + margin;
      const bool to_right = r.cb.hi[axis] >= split - margin;
      if (to_left && to_right) {
        left.push_back({r.id, clip_into_child(prims_, r.id, lbox, margin)});
        right.push_back({r.id, clip_into_child(prims_, r.id, rbox, margin)});
      } else if (to_left) {
        left.push_back(r);
      } else {
        right.push_back(r);
      }
    }
  }

  static void make_leaf(const std::vector<Ref>& refs, KdBuffer& out) {
    std::vector<uint32_t> ids(refs.size());
    for (size_t i = 0; i < refs.size(); ++i) ids[i] = refs[i].id;
    std::sort(ids.begin(), ids.end());
    out.nodes.push_back(out.make_leaf(ids));
  }

  /// Nodes at least this large build their children in parallel.
  static constexpr size_t kParallelMin = 16384;
  const P& prims_;
  KdMedianConfig config_;
  int depth_limit_;
};

}  // namespace ab
