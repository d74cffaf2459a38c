// k-d trees over a primitive set: `kdtree-median` (median splits, kd_median.h) and `kdtree-sah` (the
// O(N log N) SAH build of Wald and Havran 2006, kd_events.h). Both share the compact node (kd_node.h) and
// the traversal below.
#pragma once

#include "accel/accelerator.h"
#include "accel/kd_events.h"
#include "accel/kd_median.h"
#include "accel/kd_node.h"
#include "accel/params.h"
#include "accel/split_plane.h"

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
class KdTree final : public AcceleratorBase<KdTree<P, M>> {
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
    }
    max_depth_ = int(params.get_int("max_depth", 0, 0, 100));
    config_ = params.effective();
  }

  std::string name() const override { return M == KdMethod::kSah ? "kdtree-sah" : "kdtree-median"; }
  nlohmann::json config() const override { return config_; }
  AABB bounds() const override { return prims_->bounds(); }

  /// Closest hit: front-to-back traversal with a stack of far children.
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    intersect_id_list<kCount>(*prims_, unbounded_.data(), uint32_t(unbounded_.size()), ray, best, inst, c);
    float t0 = ray.tmin, t1 = ray.tmax;
    if (nodes_.empty() || !slab_test(box_, RayBoxData(ray), t0, t1)) return;
    const RayAxes axes(ray);
    StackItem stack[kStackSize];
    int sp = 0;
    uint32_t node = 0;
    while (true) {
      const KdNode& n = nodes_[node];
      if constexpr (kCount) ++c.nodes;
      if (!n.is_leaf()) {
        if (step(n, node, axes, t0, t1, stack, sp)) continue;
      } else {
        if constexpr (kCount) ++c.leaves;
        intersect_id_list<kCount>(*prims_, &prims_ids_[n.first()], n.count(), ray, best, inst, c);
      }
      if (!pop(stack, sp, best.t, node, t0, t1)) return;
    }
  }

  /// Any hit: the same traversal, stopping at the first primitive that blocks the ray.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    if (occluded_id_list<kCount>(*prims_, unbounded_.data(), uint32_t(unbounded_.size()), ray, c)) return true;
    float t0 = ray.tmin, t1 = ray.tmax;
    if (nodes_.empty() || !slab_test(box_, RayBoxData(ray), t0, t1)) return false;
    const RayAxes axes(ray);
    StackItem stack[kStackSize];
    int sp = 0;
    uint32_t node = 0;
    while (true) {
      const KdNode& n = nodes_[node];
      if constexpr (kCount) ++c.nodes;
      if (!n.is_leaf()) {
        if (step(n, node, axes, t0, t1, stack, sp)) continue;
      } else {
        if constexpr (kCount) ++c.leaves;
        if (occluded_id_list<kCount>(*prims_, &prims_ids_[n.first()], n.count(), ray, c)) return true;
      }
      if (!pop(stack, sp, kInf, node, t0, t1)) return false;
    }
  }

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
    nodes_ = std::move(out.nodes);
    prims_ids_ = std::move(out.prims);
    fill_stats(depth);
  }

 private:
  struct StackItem {
    uint32_t node;
    float t0, t1;
  };
  static constexpr int kStackSize = 128;

  /// One interior node: continues into the first child met (pushing the second) and returns true, or
  /// returns false when neither child overlaps the interval.
  [[gnu::always_inline]] bool step(const KdNode& n, uint32_t& node, const RayAxes& r, float& t0, float& t1, StackItem* stack,
            int& sp) const {
    const int a = n.axis();
    const PlaneVisit v = split_at_axis_plane(r.org[a], r.dir[a], r.inv[a], n.split(), t0, t1);
    const uint32_t first = v.first_below ? node + 1 : n.above();
    const uint32_t second = v.first_below ? n.above() : node + 1;
    if (v.visit_first) {
      if (v.visit_second) stack[sp++] = {second, v.second_t0, t1};
      node = first;
      t1 = v.first_t1;
      return true;
    }
    if (v.visit_second) {
      node = second;
      t0 = v.second_t0;
      return true;
    }
    return false;
  }

  /// Next node from the stack whose entry is not beyond best_t (strictly); false when none is left.
  [[gnu::always_inline]] static bool pop(const StackItem* stack, int& sp, float best_t, uint32_t& node, float& t0, float& t1) {
    while (sp > 0) {
      const StackItem& it = stack[--sp];
      if (it.t0 > best_t) continue;
      node = it.node;
      t0 = it.t0;
      t1 = it.t1;
      return true;
    }
    return false;
  }

  void fill_stats(int depth_limit) {
    BuildStats& st = this->stats_;
    st.nodes = nodes_.size();
    st.bytes = nodes_.size() * sizeof(KdNode) + prims_ids_.size() * sizeof(uint32_t) +
               unbounded_.size() * sizeof(uint32_t);
    st.extra["depth_limit"] = depth_limit;
    st.extra["unbounded_primitives"] = unbounded_.size();
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
      todo.push_back({n.above(), it.depth + 1, hi});
      todo.push_back({it.node + 1, it.depth + 1, lo});
    }
    st.sah_cost = sah;
  }

  std::shared_ptr<const P> prims_;
  KdSahSettings sah_;
  KdMedianSettings median_;
  int max_depth_ = 0;
  nlohmann::json config_;
  AABB box_;
  std::vector<KdNode> nodes_;
  std::vector<uint32_t> prims_ids_;
  std::vector<uint32_t> unbounded_;
};

/// The median-split k-d tree (registry name kdtree-median).
template <class P>
using KdTreeMedian = KdTree<P, KdMethod::kMedian>;
/// The SAH k-d tree (registry name kdtree-sah).
template <class P>
using KdTreeSah = KdTree<P, KdMethod::kSah>;

}  // namespace ab
