// The motion BVH's builder (Woop, Afra, Benthin, Kensler and Wald 2017, "STBVH: a spatial-temporal BVH for
// efficient multi-segment motion blur"): every node holds a linear bound over its time range; a node is
// split either by objects (binned SAH over the centroids of the boxes at mid-range, Wald 2007) or in time
// (both children get every primitive, each over half of the range at the time step nearest its middle),
// whichever the SAH over time-weighted areas prices lower: an object split costs
// A(left) N_l + A(right) N_r, a temporal split w_l A(left) N + w_r A(right) N with w the children's shares
// of the range, A the area of a linear bound's middle box (Embree's expected half area). Large nodes build
// their children in parallel (TBB), each into a tree of its own that is then appended, whatever the number
// of threads: the same tree for any thread count.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "accel/bvh/motion_bounds.h"
#include "accel/bvh/motion_node.h"
#include "accel/common/sah.h"

namespace ab {

/// The builder's result: the nodes (the root first, every node's children a sibling pair) and the primitive
/// ids of the leaves (a primitive appears in one leaf per time range it is split into).
struct MotionBvhBuild {
  std::vector<MotionBvhNode> nodes;
  std::vector<uint32_t> refs;
};

/// The builder's settings.
struct MotionBuildSettings {
  SahCosts costs;
  int bins = 16;
  int max_leaf_size = 8;
  int max_depth = 64;
  size_t parallel_threshold = 4096;  ///< nodes at least this large build their children in parallel
};

/// Builds over primitive set P (motion_bounds.h gives each primitive's steps).
template <class P>
class MotionBvhBuilder {
 public:
  /// Prepares the build over prims.
  MotionBvhBuilder(const P& prims, MotionBuildSettings settings) : prims_(prims), settings_(settings) {}

  /// The whole tree over time range [0, 1].
  MotionBvhBuild build() {
    std::vector<uint32_t> ids(prims_.size());
    for (uint32_t i = 0; i < ids.size(); ++i) ids[i] = i;
    if (ids.empty()) return {};
    out_.nodes.resize(1);
    build_node(ids, 0.0f, 1.0f, 0, 0);
    return std::move(out_);
  }

 private:
  /// One item of a node: a primitive and its linear bound over the node's range.
  struct Item {
    uint32_t id;
    LinearBounds lb;
    vec3 centroid;
  };
  /// A candidate object split: cost, axis and bin boundary.
  struct ObjectSplit {
    float cost = kInf;
    int axis = -1;
    int bin = 0;
  };

  /// The items of ids over [t0, t1] (in parallel for large nodes) and their union into all.
  std::vector<Item> make_items(const std::vector<uint32_t>& ids, float t0, float t1,
                               LinearBounds& all) const {
    std::vector<Item> items(ids.size());
    const auto fill = [&](size_t b, size_t e) {
      for (size_t k = b; k < e; ++k) {
        items[k] = {ids[k], prim_linear_bounds(prims_, ids[k], t0, t1), {}};
        items[k].centroid = items[k].lb.middle().center();
      }
    };
    if (ids.size() >= settings_.parallel_threshold)
      tbb::parallel_for(tbb::blocked_range<size_t>(0, ids.size(), 1024),
                        [&](const tbb::blocked_range<size_t>& r) { fill(r.begin(), r.end()); });
    else
      fill(0, ids.size());
    all = {AABB{}, AABB{}};
    for (const Item& it : items) all.extend(it.lb);
    return items;
  }

  /// Node `index` over ids on [t0, t1]: a leaf, or a temporal or object split into a new sibling pair.
  void build_node(const std::vector<uint32_t>& ids, float t0, float t1, int depth, uint32_t index) {
    LinearBounds all;
    std::vector<Item> items = make_items(ids, t0, t1, all);
    out_.nodes[index] = MotionBvhNode::make(all, t0, t1);
    const size_t n = items.size();
    const float area = std::max(all.middle().area(), 1e-30f);
    const ObjectSplit object = n > 1 ? find_object_split(items, area) : ObjectSplit{};
    float tm = 0.0f;
    const float temporal = temporal_split_cost(ids, t0, t1, area, tm);
    const bool must_split = int(n) > settings_.max_leaf_size;
    if (depth + 1 >= settings_.max_depth ||
        (!must_split && settings_.costs.leaf(n) <= std::min(object.cost, temporal)) ||
        (object.axis < 0 && temporal == kInf))
      return make_leaf(index, ids);
    const auto pair = static_cast<uint32_t>(out_.nodes.size());
    out_.nodes.resize(pair + 2);
    out_.nodes[index].offset = pair;
    if (temporal < object.cost) return build_children({ids, t0, tm}, {ids, tm, t1}, n, depth + 1, pair);
    std::vector<uint32_t> left, right;
    partition(items, object, left, right);
    items.clear();
    build_children({left, t0, t1}, {right, t0, t1}, n, depth + 1, pair);
  }

  /// What a child is built over: primitives and a time range.
  struct ChildInput {
    const std::vector<uint32_t>& ids;
    float t0, t1;
  };
  /// The sibling pair at `pair` (children of a node of n primitives): in this tree, or for n at least
  /// parallel_threshold in parallel, each into a tree of its own appended after (the same layout either way
  /// for any number of threads).
  void build_children(ChildInput l, ChildInput r, size_t n, int depth, uint32_t pair) {
    if (n < settings_.parallel_threshold) {
      build_node(l.ids, l.t0, l.t1, depth, pair);
      build_node(r.ids, r.t0, r.t1, depth, pair + 1);
      return;
    }
    MotionBvhBuild left, right;
    tbb::parallel_invoke([&] { left = subtree(l, depth); }, [&] { right = subtree(r, depth); });
    append(std::move(left), pair);
    append(std::move(right), pair + 1);
  }
  /// A tree of its own over the child's input (its root at 0).
  MotionBvhBuild subtree(ChildInput in, int depth) const {
    MotionBvhBuilder sub(prims_, settings_);
    sub.out_.nodes.resize(1);
    sub.build_node(in.ids, in.t0, in.t1, depth, 0);
    return std::move(sub.out_);
  }
  /// Places sub's root at `slot` and its other nodes and references at the ends of this tree's.
  void append(MotionBvhBuild&& sub, uint32_t slot) {
    const auto base = static_cast<uint32_t>(out_.nodes.size()) - 1;  // sub's node k >= 1 goes to base + k
    const auto ref_base = static_cast<uint32_t>(out_.refs.size());
    const auto moved = [&](MotionBvhNode node) {
      node.offset += node.is_leaf() ? ref_base : base;
      return node;
    };
    out_.nodes[slot] = moved(sub.nodes[0]);
    for (size_t k = 1; k < sub.nodes.size(); ++k) out_.nodes.push_back(moved(sub.nodes[k]));
    out_.refs.insert(out_.refs.end(), sub.refs.begin(), sub.refs.end());
  }

  void make_leaf(uint32_t index, const std::vector<uint32_t>& ids) {
    out_.nodes[index].offset = static_cast<uint32_t>(out_.refs.size());
    out_.nodes[index].count = static_cast<uint32_t>(ids.size());
    out_.refs.insert(out_.refs.end(), ids.begin(), ids.end());
  }

  /// Bins of the centroids' bounds on one axis (0 when they have no extent there).
  static int bin_of(float c, float lo, float scale, int bins) {
    return std::clamp(static_cast<int>((c - lo) * scale), 0, bins - 1);
  }

  /// Binned SAH over the centroids of the middle boxes, on every axis (Wald 2007).
  ObjectSplit find_object_split(const std::vector<Item>& items, float area) const {
    AABB cb;
    for (const Item& it : items) cb.extend(it.centroid);
    ObjectSplit best;
    const int bins = settings_.bins;
    for (int axis = 0; axis < 3; ++axis) {
      const float extent = cb.hi[axis] - cb.lo[axis];
      if (!(extent > 0.0f)) continue;
      const float scale = float(bins) / extent;
      std::vector<LinearBounds> box(size_t(bins), LinearBounds{AABB{}, AABB{}});
      std::vector<size_t> count(size_t(bins), 0);
      for (const Item& it : items) {
        const int b = bin_of(it.centroid[axis], cb.lo[axis], scale, bins);
        box[size_t(b)].extend(it.lb);
        ++count[size_t(b)];
      }
      std::vector<float> right_area(size_t(bins), 0.0f);
      std::vector<size_t> right_n(size_t(bins), 0);
      LinearBounds acc{AABB{}, AABB{}};
      size_t acc_n = 0;
      for (int b = bins - 1; b > 0; --b) {
        acc.extend(box[size_t(b)]);
        acc_n += count[size_t(b)];
        right_area[size_t(b)] = acc.middle().area();
        right_n[size_t(b)] = acc_n;
      }
      acc = {AABB{}, AABB{}};
      acc_n = 0;
      for (int b = 1; b < bins; ++b) {
        acc.extend(box[size_t(b - 1)]);
        acc_n += count[size_t(b - 1)];
        if (acc_n == 0 || right_n[size_t(b)] == 0) continue;
        const float cost = settings_.costs.split(area, acc.middle().area(), acc_n, right_area[size_t(b)],
                                                 right_n[size_t(b)]);
        if (cost < best.cost) best = {cost, axis, b};
      }
    }
    return best;
  }

  /// The cost of splitting [t0, t1] at the time step nearest its middle (tm), or inf when no primitive has
  /// a time step strictly inside the range.
  float temporal_split_cost(const std::vector<uint32_t>& ids, float t0, float t1, float area,
                            float& tm) const {
    uint32_t steps = 1;
    for (uint32_t id : ids) steps = std::max(steps, motion_steps(prims_, id));
    if (steps <= 2) return kInf;
    const float segments = float(steps - 1);
    tm = std::round(0.5f * (t0 + t1) * segments) / segments;
    if (!(tm > t0 && tm < t1)) {
      tm = std::floor(t0 * segments + 1.0f) / segments;
      if (!(tm > t0 && tm < t1)) return kInf;
    }
    // Both halves' bounds, by chunks of 1024 (in parallel for large nodes; a union of boxes is exact, so
    // the result does not depend on the order).
    const size_t chunks = (ids.size() + 1023) / 1024;
    std::vector<LinearBounds> lefts(chunks, LinearBounds{AABB{}, AABB{}}), rights = lefts;
    const auto chunk = [&](size_t c) {
      for (size_t k = c * 1024, e = std::min(ids.size(), k + 1024); k < e; ++k) {
        lefts[c].extend(prim_linear_bounds(prims_, ids[k], t0, tm));
        rights[c].extend(prim_linear_bounds(prims_, ids[k], tm, t1));
      }
    };
    if (ids.size() >= settings_.parallel_threshold)
      tbb::parallel_for(size_t(0), chunks, chunk);
    else
      for (size_t c = 0; c < chunks; ++c) chunk(c);
    LinearBounds left{AABB{}, AABB{}}, right{AABB{}, AABB{}};
    for (size_t c = 0; c < chunks; ++c) left.extend(lefts[c]), right.extend(rights[c]);
    const float wl = (tm - t0) / (t1 - t0), wr = 1.0f - wl;
    return settings_.costs.split(area, wl * left.middle().area(), ids.size(), wr * right.middle().area(),
                                 ids.size());
  }

  /// The items by the split's bin boundary (the same binning as find_object_split).
  void partition(const std::vector<Item>& items, const ObjectSplit& split, std::vector<uint32_t>& left,
                 std::vector<uint32_t>& right) const {
    AABB cb;
    for (const Item& it : items) cb.extend(it.centroid);
    const int axis = split.axis;
    const float scale = float(settings_.bins) / (cb.hi[axis] - cb.lo[axis]);
    for (const Item& it : items)
      (bin_of(it.centroid[axis], cb.lo[axis], scale, settings_.bins) < split.bin ? left : right)
          .push_back(it.id);
  }

  const P& prims_;
  MotionBuildSettings settings_;
  MotionBvhBuild out_;
};

}  // namespace ab
