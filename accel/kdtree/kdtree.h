// k-d trees over a primitive set: `kdtree-median` (median splits, kd_median.h) and `kdtree-sah` (the
// O(N log N) SAH build of Wald and Havran 2006, kd_events.h). Both share the compact node (kd_node.h) and
// the traversal below.
#pragma once

#include "accel/core/box_test.h"
#include "accel/core/accelerator.h"
#include "accel/kdtree/sah_builder.h"
#include "accel/kdtree/median_builder.h"
#include "accel/common/spatial_tree.h"
#include "accel/core/params.h"
#include "accel/common/split_plane.h"

#include <memory>
#include <string>
#include <vector>

namespace ab {

/// Which builder a k-d tree uses.
enum class KdMethod { kMedian, kSah };

/// A k-d tree. Traversal: Havran's front-to-back stack traversal (Havran 2000, TA_B rec), one robust
/// plane step (split_plane.h) per interior node, leaves pruned only when their entry lies strictly
/// beyond the best hit so far.
template <class P, KdMethod M>
class KdTree final : public SpatialTreeQueries<KdTree<P, M>> {
  friend class SpatialTreeQueries<KdTree<P, M>>;

 public:
  /// Reads the configuration from params (see config() for the fields).
  KdTree(std::shared_ptr<const P> prims, Params& params) : prims_(std::move(prims)) {
    if constexpr (M == KdMethod::kSah) {
      sah_.traversal_cost = float(params.get_float("traversal_cost", 1.0, 1e-3, 1e6));
      sah_.intersection_cost = float(params.get_float("intersection_cost", 1.5, 1e-3, 1e6));
      sah_.empty_bonus = float(params.get_float("empty_bonus", 0.2, 0.0, 0.99));
    } else {
      median_.leaf_size = size_t(params.get_int("leaf_size", 4, 1, 1 << 20));
      median_.cycle_axes = params.get_choice("axis", "longest", {"longest", "cycle"}) == "cycle";
      median_.straddle_limit = params.get_float("straddle_limit", 0.75, 0.0, 1.0);
    }
    max_depth_ = int(params.get_int("max_depth", 0, 0, 100));
    leaf_copies_ = read_leaf_copies(params);
    config_ = params.effective();
  }

  std::string name() const override { return M == KdMethod::kSah ? "kdtree-sah" : "kdtree-median"; }
  nlohmann::json config() const override { return config_; }
  AABB bounds() const override { return prims_->bounds(); }

 protected:
  void do_build() override {
    BuildStats& st = this->stats_;
    st = BuildStats{};
    st.primitives = prims_->size();
    // NaN or infinite coordinates: tested for every ray.
    std::vector<uint32_t> ids = partition_finite(*prims_, unbounded_, box_);
    KdBuffer out;
    const int depth = max_depth_ > 0 ? max_depth_ : auto_kd_depth(ids.size());
    if (!ids.empty()) {
      if constexpr (M == KdMethod::kSah) {
        KdSahSettings s = sah_;
        s.max_depth = depth;
        KdSahBuilder<P>(*prims_, s).build(ids, box_, out);
      } else {
        KdMedianSettings s = median_;
        s.max_depth = depth;
        KdMedianBuilder<P>(*prims_, s).build(ids, box_, out);
      }
    }
    drop_empty_leaves(out.nodes);
    margin_ = ids.empty() ? 0.0f : insertion_margin(box_);
    root_box_ = {box_.lo - vec3(margin_), box_.hi + vec3(margin_)};
    nodes_ = std::move(out.nodes);
    leaves_.assign(*prims_, std::move(out.prims), leaf_copies_);
    fill_stats(depth);
  }

 private:
  struct StackItem {
    uint32_t node;
    float t0, t1;
  };
  static constexpr int kStackSize = 128;

  /// Front-to-back traversal (Havran 2000, TA_B rec, in the tight form of pbrt's KdTreeAggregate): at an
  /// interior node the ray interval [t0, t1] is split at the plane's widened crossing (AxisRay), the
  /// first child continues and the second, when the interval reaches it, goes on the stack. leaf(first,
  /// count) returns true to stop (any hit); an entry is popped only when its t0 is not beyond best_t().
  template <bool kCount, class Leaf, class BestT>
  [[gnu::always_inline]] bool traverse(const Ray& ray, RayCounters& c, Leaf&& leaf, BestT&& best_t) const {
    float t0 = ray.tmin, t1 = ray.tmax;
    if (nodes_.empty() || !slab_test(root_box_, RayBoxData(ray), t0, t1)) return false;
    const AxisRay r(ray, margin_);
    const KdNode* nodes = nodes_.data();
    StackItem stack[kStackSize];
    int sp = 0;
    uint32_t idx = 0;
    for (;;) {
      KdNode n = nodes[idx];
      while (!n.is_leaf()) {
        if constexpr (kCount) ++c.nodes;
        const AxisCrossing x = r.cross(n.axis(), n.split());
        const uint32_t below = idx + 1, above = n.above();
        const uint32_t first = x.below_first ? below : above;
        const uint32_t second = x.below_first ? above : below;
        const bool first_empty = x.below_first ? n.below_empty() : n.above_empty();
        const bool second_empty = x.below_first ? n.above_empty() : n.below_empty();
        const bool visit_first = !(x.far < t0) && !first_empty;
        const bool visit_second = !(x.near > t1) && !second_empty;
        if (visit_first) {
          if (visit_second) stack[sp++] = {second, std::max(t0, x.near), t1};
          t1 = std::min(t1, x.far);
          idx = first;
        } else if (visit_second) {
          t0 = std::max(t0, x.near);
          idx = second;
        } else {
          goto pop;  // only an empty child lies in the interval
        }
        n = nodes[idx];
      }
      if constexpr (kCount) {
        ++c.nodes;
        ++c.leaves;
      }
      if (n.count() && leaf(n.first(), n.count())) return true;
    pop:
      const float limit = best_t();
      do {
        if (sp == 0) return false;
        --sp;
      } while (stack[sp].t0 > limit);
      idx = stack[sp].node;
      t0 = stack[sp].t0;
      t1 = stack[sp].t1;
    }
  }

  void fill_stats(int depth_limit) {
    BuildStats& st = this->stats_;
    st.nodes = nodes_.size();
    st.bytes = nodes_.size() * sizeof(KdNode) + leaves_.bytes() + unbounded_.size() * sizeof(uint32_t);
    st.extra["depth_limit"] = depth_limit;
    st.extra["unbounded_primitives"] = unbounded_.size();
    st.extra["leaf_copies"] = leaves_.copied();
    if (nodes_.empty()) return;
    const double root_area = box_.area();
    struct Item {
      uint32_t node;
      uint32_t depth;
      AABB box;
    };
    std::vector<Item> todo{{0, 0, box_}};
    double sah = 0.0;
    while (!todo.empty()) {
      const Item it = todo.back();
      todo.pop_back();
      const KdNode& n = nodes_[it.node];
      const double p = root_area > 0.0 ? it.box.area() / root_area : 1.0;
      if (n.is_leaf()) {
        st.add_leaf(n.count(), it.depth);
        sah += p * n.count();
        continue;
      }
      sah += p;
      AABB lo = it.box, hi = it.box;
      lo.hi[n.axis()] = n.split();
      hi.lo[n.axis()] = n.split();
      if (n.above_empty()) st.add_leaf(0, it.depth + 1);
      else todo.push_back({n.above(), it.depth + 1, hi});
      if (n.below_empty()) st.add_leaf(0, it.depth + 1);
      else todo.push_back({it.node + 1, it.depth + 1, lo});
    }
    st.extra["stored_nodes"] = nodes_.size();  // nodes: also the empty leaves, which are flags, not nodes
    st.nodes = 2 * st.leaves - 1;
    st.sah_cost = sah;
  }

  std::shared_ptr<const P> prims_;
  KdSahSettings sah_;
  KdMedianSettings median_;
  int max_depth_ = 0;
  LeafCopies leaf_copies_ = LeafCopies::kAuto;  ///< copy triangles into leaf order (LeafRefs)
  nlohmann::json config_;
  AABB box_;
  AABB root_box_;       ///< box_ grown by margin_ (the traversal's first clip)
  float margin_ = 0.0f;  ///< positional band of every plane crossing (AxisRay)
  std::vector<KdNode> nodes_;
  LeafRefs<P> leaves_;
  std::vector<uint32_t> unbounded_;
};

/// The median-split k-d tree (registry name kdtree-median).
template <class P>
using KdTreeMedian = KdTree<P, KdMethod::kMedian>;
/// The SAH k-d tree (registry name kdtree-sah).
template <class P>
using KdTreeSah = KdTree<P, KdMethod::kSah>;

}  // namespace ab
