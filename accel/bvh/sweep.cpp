// The full-sweep SAH BVH builder (bvh-sweep).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstring>

#include "accel/bvh/build.h"
#include "accel/bvh/sah_split.h"
#include "accel/bvh/slots.h"

namespace ab {

namespace {

/// A reference in one of the three sorted lists: bounds and id (the centroid is only needed to sort).
struct SweepRef {
  AABB box;
  uint32_t id;
};

/// A sort key: the centroid coordinate on one axis and the id that breaks ties.
struct SortKey {
  float c;
  uint32_t id;

  bool operator<(const SortKey& o) const { return c != o.c ? c < o.c : id < o.id; }
};

// Full-sweep SAH (MacDonald and Booth 1990) in O(N log N): the references are sorted by centroid on each of
// the three axes once, at the root (ties by id). At every node each sorted list is swept, suffix areas
// right to left and then prefix areas and costs left to right, so every split between consecutive
// primitives is evaluated with exact child bounds; once the split is chosen, the primitives are marked
// left or right in the chosen axis' order and the two other lists are partitioned stably in linear time,
// which keeps every list sorted (the presorting scheme Wald and Havran 2006 use for k-d trees, applied to
// object partitioning). The tree equals the one of re-sorting at every node, and is the same for any
// number of threads: every decision depends only on the node's range.
class SweepBuilder {
 public:
  SweepBuilder(const BvhSweepConfig& config, std::span<const AABB> bounds, std::span<const vec3> centroids);

  /// Builds the tree and returns the flattened result.
  BvhBuildResult run();

 private:
  void sort_axis(int a, std::span<const AABB> bounds);
  void build(uint32_t p, uint32_t b, uint32_t e, const AABB& box, int depth);
  SahSplit find_split(uint32_t b, uint32_t e, float area);
  void sweep_axis(int a, uint32_t b, uint32_t e, float area, SahSplit& best);
  void partition(int a, uint32_t b, uint32_t m, uint32_t e, AABB& left, AABB& right);

  const BvhSweepConfig& config_;
  std::span<const vec3> centroids_;
  std::array<std::vector<SweepRef>, 3> lists_;  ///< per axis, each node's range sorted by (centroid, id)
  std::vector<SweepRef> scratch_;               ///< partition buffer (ranges of parallel nodes are disjoint)
  std::vector<float> right_area_;               ///< suffix areas of the sweep, by position
  std::vector<uint8_t> goes_left_;              ///< side of each id in the current partition
  BvhSlots slots_;
  AABB root_box_;
};

SweepBuilder::SweepBuilder(const BvhSweepConfig& config, std::span<const AABB> bounds,
                           std::span<const vec3> centroids)
    : config_(config),
      centroids_(centroids),
      scratch_(bounds.size()),
      right_area_(bounds.size()),
      goes_left_(bounds.size()),
      slots_(bounds.size()) {
  for (const AABB& b : bounds) root_box_.extend(b);
  for (int a = 0; a < 3; ++a) sort_axis(a, bounds);
}

/// Sorts the references on axis a by (centroid, id) into lists_[a].
void SweepBuilder::sort_axis(int a, std::span<const AABB> bounds) {
  const size_t n = bounds.size();
  std::vector<SortKey> keys(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1u << 14), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) keys[i] = {centroids_[i][a], uint32_t(i)};
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  lists_[a].resize(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1u << 14), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) lists_[a][k] = {bounds[keys[k].id], keys[k].id};
  });
}

BvhBuildResult SweepBuilder::run() {
  const size_t n = lists_[0].size();
  if (n > 0) build(0, 0, uint32_t(n), root_box_, 0);
  std::vector<uint32_t> order(n);
  for (size_t k = 0; k < n; ++k) order[k] = lists_[0][k].id;
  return flatten_bvh_slots(slots_, std::move(order));
}

void SweepBuilder::build(uint32_t p, uint32_t b, uint32_t e, const AABB& box, int depth) {
  slots_.set_box(p, box);
  const uint32_t n = e - b;
  SahSplit best;
  uint32_t decision = 0;
  if (depth < config_.max_depth && n > 1) {
    best = find_split(b, e, box.area());
    decision = sah_decision(n, best, config_);
  }
  if (decision == 0) {
    slots_.set_leaf(p, b, e);
    return;
  }
  // A forced split (no valid SAH split, too many primitives) halves the node in the order of list 0.
  const int axis = decision == n ? best.axis : 0;
  const uint32_t m = b + (decision == n ? uint32_t(best.position) : decision);
  AABB left, right;
  partition(axis, b, m, e, left, right);
  const uint32_t right_slot = slots_.set_interior(p, b, m);
  auto build_left = [&] { build(p + 1, b, m, left, depth + 1); };
  auto build_right = [&] { build(right_slot, m, e, right, depth + 1); };
  if (n >= config_.parallel_threshold) {
    tbb::parallel_invoke(build_left, build_right);
  } else {
    build_left();
    build_right();
  }
}

/// The cheapest split over the three axes; an axis whose centroids all coincide is skipped.
SahSplit SweepBuilder::find_split(uint32_t b, uint32_t e, float area) {
  SahSplit best;
  for (int a = 0; a < 3; ++a) {
    const float first = centroids_[lists_[a][b].id][a], last = centroids_[lists_[a][e - 1].id][a];
    if (last > first) sweep_axis(a, b, e, area, best);
  }
  return best;
}

/// Evaluates every split between consecutive primitives of list a over [b, e) and updates best.
void SweepBuilder::sweep_axis(int a, uint32_t b, uint32_t e, float area, SahSplit& best) {
  const SweepRef* refs = lists_[a].data();
  float* right_area = right_area_.data();
  const uint32_t n = e - b;
  AABB acc;
  for (uint32_t i = n - 1; i > 0; --i) {
    acc.extend(refs[b + i].box);
    right_area[b + i] = acc.area();
  }
  acc = AABB{};
  for (uint32_t i = 1; i < n; ++i) {
    acc.extend(refs[b + i - 1].box);
    const float c = config_.costs.split(area, acc.area(), i, right_area[b + i], n - i);
    if (c < best.cost) best = {a, int(i), c};
  }
}

/// Splits [b, e) at m in list a's order: marks the sides, gathers the child boxes, and partitions the two
/// other lists stably (each stays sorted) through the scratch buffer.
void SweepBuilder::partition(int a, uint32_t b, uint32_t m, uint32_t e, AABB& left, AABB& right) {
  const SweepRef* sorted = lists_[a].data();
  for (uint32_t k = b; k < m; ++k) {
    goes_left_[sorted[k].id] = 1;
    left.extend(sorted[k].box);
  }
  for (uint32_t k = m; k < e; ++k) {
    goes_left_[sorted[k].id] = 0;
    right.extend(sorted[k].box);
  }
  for (int o = 0; o < 3; ++o) {
    if (o == a) continue;
    SweepRef* list = lists_[o].data();
    uint32_t l = b, r = m;
    for (uint32_t k = b; k < e; ++k) scratch_[goes_left_[list[k].id] ? l++ : r++] = list[k];
    std::memcpy(list + b, scratch_.data() + b, size_t(e - b) * sizeof(SweepRef));
  }
}

}  // namespace

BvhBuildResult build_bvh(const BvhSweepConfig& config, std::span<const AABB> bounds,
                         std::span<const vec3> centroids) {
  return SweepBuilder(config, bounds, centroids).run();
}

}  // namespace ab
