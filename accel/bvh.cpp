#include "accel/bvh.h"

#include "accel/registry.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <numeric>

namespace ab {

namespace {

/// Ranges at least this large compute their bounds and bins with a parallel reduction. The reductions
/// use only min, max and integer sums, which are exact, so the result does not depend on the split.
constexpr size_t kParallelReduceThreshold = 1u << 16;
constexpr size_t kGrain = 1u << 12;

/// Bounds of the primitives of a range and of their centroids.
struct RangeBounds {
  AABB bounds;
  AABB centroids;

  void merge(const RangeBounds& o) {
    bounds.extend(o.bounds);
    centroids.extend(o.centroids);
  }
};

/// A primitive as the builder moves it around: bounds, centroid and id together, so the passes over a
/// range read contiguous memory.
struct BuildRef {
  AABB box;
  vec3 centroid;
  uint32_t id;
};

/// The builder: recursion over ranges of the reference array `refs_`. A node for range [b, e) is
/// written at slot p of a gapped array of 2N-1 slots; its left child is at p+1 and its right child at
/// p + 2 (m - b), so disjoint subtrees never share slots and can be built in parallel. flatten() then
/// compacts the slots into the final array.
class BvhBuilder {
 public:
  BvhBuilder(BvhMethod method, const BvhConfig& config, std::span<const AABB> bounds, std::span<const vec3> centroids)
      : method_(method), config_(config), refs_(bounds.size()), slots_(bounds.empty() ? 0 : 2 * bounds.size() - 1) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, refs_.size(), kGrain), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) refs_[i] = {bounds[i], centroids[i], uint32_t(i)};
    });
  }

  /// Builds the tree and returns the flattened result.
  BvhBuildResult run() {
    if (!refs_.empty()) build(0, 0, uint32_t(refs_.size()), 0);
    return flatten();
  }

 private:
  void build(uint32_t p, uint32_t b, uint32_t e, int depth);
  RangeBounds range_bounds(uint32_t b, uint32_t e) const;
  uint32_t choose_split(uint32_t b, uint32_t e, const RangeBounds& rb);
  uint32_t split_median(uint32_t b, uint32_t e, const RangeBounds& rb);
  uint32_t split_binned(uint32_t b, uint32_t e, const RangeBounds& rb);
  uint32_t split_sweep(uint32_t b, uint32_t e, const RangeBounds& rb);
  std::vector<SahBin> bin_range(uint32_t b, uint32_t e, const BinMapping& map) const;
  uint32_t decide(uint32_t b, uint32_t e, const SahSplit& best) const;
  BvhBuildResult flatten() const;

  BvhMethod method_;
  BvhConfig config_;
  std::vector<BuildRef> refs_;
  std::vector<BvhNode> slots_;
};

void BvhBuilder::build(uint32_t p, uint32_t b, uint32_t e, int depth) {
  const RangeBounds rb = range_bounds(b, e);
  BvhNode& node = slots_[p];
  for (int a = 0; a < 3; ++a) {
    node.lo[a] = rb.bounds.lo[a];
    node.hi[a] = rb.bounds.hi[a];
  }
  const uint32_t m = (depth >= config_.max_depth || e - b == 1) ? b : choose_split(b, e, rb);
  if (m == b) {  // leaf
    node.offset = b;
    node.count = e - b;
    return;
  }
  const uint32_t left = p + 1, right = p + 2 * (m - b);
  node.offset = right;
  node.count = 0;
  if (e - b >= config_.parallel_threshold) {
    tbb::parallel_invoke([&] { build(left, b, m, depth + 1); }, [&] { build(right, m, e, depth + 1); });
  } else {
    build(left, b, m, depth + 1);
    build(right, m, e, depth + 1);
  }
}

RangeBounds BvhBuilder::range_bounds(uint32_t b, uint32_t e) const {
  auto body = [&](const tbb::blocked_range<uint32_t>& r, RangeBounds acc) {
    for (uint32_t k = r.begin(); k < r.end(); ++k) {
      acc.bounds.extend(refs_[k].box);
      acc.centroids.extend(refs_[k].centroid);
    }
    return acc;
  };
  if (e - b < kParallelReduceThreshold) return body({b, e}, RangeBounds{});
  return tbb::parallel_reduce(tbb::blocked_range<uint32_t>(b, e, kGrain), RangeBounds{}, body,
                              [](RangeBounds x, const RangeBounds& y) {
                                x.merge(y);
                                return x;
                              });
}

/// Returns the split index m in (b, e), or b for a leaf.
uint32_t BvhBuilder::choose_split(uint32_t b, uint32_t e, const RangeBounds& rb) {
  switch (method_) {
    case BvhMethod::kMedian:
      return split_median(b, e, rb);
    case BvhMethod::kBinnedSah:
      return split_binned(b, e, rb);
    case BvhMethod::kSweepSah:
      return split_sweep(b, e, rb);
  }
  return b;
}

// Object median: sort-free selection (nth_element) of the centroid median along the longest axis of
// the centroid bounds; ties broken by id so the result is a function of the range alone.
uint32_t BvhBuilder::split_median(uint32_t b, uint32_t e, const RangeBounds& rb) {
  const uint32_t n = e - b;
  if (n <= uint32_t(config_.max_leaf_size)) return b;
  const int axis = rb.centroids.longest_axis();
  const uint32_t m = b + n / 2;
  if (!(rb.centroids.extent()[axis] > 0.0f)) return m;  // all centroids coincide: split by position
  std::nth_element(refs_.begin() + b, refs_.begin() + m, refs_.begin() + e, [&](const BuildRef& x, const BuildRef& y) {
    const float cx = x.centroid[axis], cy = y.centroid[axis];
    return cx != cy ? cx < cy : x.id < y.id;
  });
  return m;
}

/// Leaf or split given the best SAH split: a leaf when the SAH says splitting does not pay and the node
/// is small enough; a forced split in the middle when no valid split exists but the node is too big.
uint32_t BvhBuilder::decide(uint32_t b, uint32_t e, const SahSplit& best) const {
  const uint32_t n = e - b;
  const bool small = n <= uint32_t(config_.max_leaf_size);
  if (best.axis < 0) return small ? b : b + n / 2;
  if (small && best.cost >= config_.costs.leaf(n)) return b;
  return e;  // "split as found"
}

std::vector<SahBin> BvhBuilder::bin_range(uint32_t b, uint32_t e, const BinMapping& map) const {
  const size_t nb = size_t(map.bins);
  auto body = [&](const tbb::blocked_range<uint32_t>& r, std::vector<SahBin> acc) {
    if (acc.empty()) acc.resize(3 * nb);
    for (uint32_t k = r.begin(); k < r.end(); ++k) {
      const BuildRef& ref = refs_[k];
      for (int a = 0; a < 3; ++a) acc[a * nb + map.bin(a, ref.centroid[a])].add(ref.box);
    }
    return acc;
  };
  if (e - b < kParallelReduceThreshold) return body({b, e}, std::vector<SahBin>(3 * nb));
  return tbb::parallel_reduce(tbb::blocked_range<uint32_t>(b, e, kGrain), std::vector<SahBin>(3 * nb), body,
                              [](std::vector<SahBin> x, const std::vector<SahBin>& y) {
                                for (size_t i = 0; i < x.size(); ++i) x[i].merge(y[i]);
                                return x;
                              });
}

// Binned SAH (Wald 2007): centroids are projected into equal-width bins on each axis, the bins are
// swept to evaluate every bin boundary, and the range is partitioned at the cheapest one.
uint32_t BvhBuilder::split_binned(uint32_t b, uint32_t e, const RangeBounds& rb) {
  // Small nodes use as many bins as primitives (more could not separate them any better on average, and
  // evaluating unused boundaries dominates the cost near the leaves).
  const BinMapping map(rb.centroids, std::min(config_.bins, std::max(4, int(e - b))));
  const std::vector<SahBin> bins = bin_range(b, e, map);
  SahSplit best;
  const float area = rb.bounds.area();
  for (int a = 0; a < 3; ++a)
    if (map.scale[a] > 0.0f) best_bin_split(&bins[a * size_t(map.bins)], map.bins, a, area, config_.costs, best);
  const uint32_t d = decide(b, e, best);
  if (d != e) return d;
  const auto mid = std::partition(refs_.begin() + b, refs_.begin() + e, [&](const BuildRef& ref) {
    return map.bin(best.axis, ref.centroid[best.axis]) < best.position;
  });
  return uint32_t(mid - refs_.begin());
}

// Full sweep SAH (MacDonald and Booth 1990, as the reference in Wald 2007): on each axis the centroids
// are sorted and every split between consecutive primitives is evaluated with exact child bounds.
uint32_t BvhBuilder::split_sweep(uint32_t b, uint32_t e, const RangeBounds& rb) {
  const uint32_t n = e - b;
  std::vector<uint32_t> sorted(n), best_sorted;  // positions in refs_
  std::iota(sorted.begin(), sorted.end(), b);
  std::vector<float> right_area(n);
  SahSplit best;
  const float area = rb.bounds.area();
  for (int a = 0; a < 3; ++a) {
    if (!(rb.centroids.extent()[a] > 0.0f)) continue;  // all centroids on one plane: no split on this axis
    std::sort(sorted.begin(), sorted.end(), [&](uint32_t x, uint32_t y) {
      const float cx = refs_[x].centroid[a], cy = refs_[y].centroid[a];
      return cx != cy ? cx < cy : refs_[x].id < refs_[y].id;
    });
    AABB acc;
    for (uint32_t i = n - 1; i > 0; --i) {
      acc.extend(refs_[sorted[i]].box);
      right_area[i] = acc.area();
    }
    acc = AABB{};
    const float before = best.cost;
    for (uint32_t i = 1; i < n; ++i) {
      acc.extend(refs_[sorted[i - 1]].box);
      const float c = config_.costs.split(area, acc.area(), i, right_area[i], n - i);
      if (c < best.cost) best = {a, int(i), c};
    }
    if (best.cost < before) best_sorted = sorted;
  }
  const uint32_t d = decide(b, e, best);
  if (d != e) return d;
  std::vector<BuildRef> permuted(n);
  for (uint32_t i = 0; i < n; ++i) permuted[i] = refs_[best_sorted[i]];
  std::copy(permuted.begin(), permuted.end(), refs_.begin() + b);
  return b + uint32_t(best.position);
}

/// Compacts the gapped slots into the final array: root at 0, padding at 1, then sibling pairs allocated
/// in depth-first order (a node's children pair is allocated when the node is reached), and gathers the
/// statistics.
BvhBuildResult BvhBuilder::flatten() const {
  BvhBuildResult out;
  out.order.resize(refs_.size());
  for (size_t k = 0; k < refs_.size(); ++k) out.order[k] = refs_[k].id;
  out.stats.primitives = refs_.size();
  if (slots_.empty()) return out;
  struct Item {
    uint32_t slot, index, depth;
  };
  out.nodes.resize(2);
  out.nodes[1] = BvhNode{{kInf, kInf, kInf}, 0, {-kInf, -kInf, -kInf}, 1};  // padding, never visited
  std::vector<Item> stack{{0, 0, 0}};
  SahCostAccumulator sah(slots_[0].box().area());
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    BvhNode node = slots_[it.slot];
    if (node.is_leaf()) {
      out.stats.add_leaf(node.count, it.depth);
      sah.add_leaf(node.box().area(), node.count);
    } else {
      sah.add_interior(node.box().area());
      const uint32_t pair = uint32_t(out.nodes.size());
      out.nodes.resize(pair + 2);
      stack.push_back({node.offset, pair + 1, it.depth + 1});
      stack.push_back({it.slot + 1, pair, it.depth + 1});
      node.offset = pair;
    }
    out.nodes[it.index] = node;
  }
  out.stats.nodes = out.nodes.size() - 1;  // without the padding node
  out.stats.sah_cost = sah.cost();
  return out;
}

}  // namespace

BvhBuildResult build_bvh(BvhMethod method, const BvhConfig& config, std::span<const AABB> bounds,
                         std::span<const vec3> centroids) {
  return BvhBuilder(method, config, bounds, centroids).run();
}

const char* bvh_method_name(BvhMethod method) {
  switch (method) {
    case BvhMethod::kMedian:
      return "bvh-median";
    case BvhMethod::kBinnedSah:
      return "bvh-sah";
    case BvhMethod::kSweepSah:
      return "bvh-sweep";
  }
  return "bvh";
}

BvhConfig read_bvh_config(BvhMethod method, Params& params) {
  BvhConfig c;
  if (method == BvhMethod::kMedian) {
    c.max_leaf_size = int(params.get_int("leaf_size", 4, 1, 1 << 20));
  } else {
    c.max_leaf_size = int(params.get_int("max_leaf_size", 8, 1, 1 << 20));
    if (method == BvhMethod::kBinnedSah) c.bins = int(params.get_int("bins", 16, 2, 256));
    c.costs.traversal = float(params.get_float("traversal_cost", 1.0, 0.0, 1e6));
    c.costs.intersection = float(params.get_float("intersection_cost", 1.0, 1e-6, 1e6));
  }
  c.max_depth = int(params.get_int("max_depth", 64, 1, kBvhMaxDepth));
  return c;
}

namespace {
const Registrar kRegisterMedian{structure_info<BvhMedian>(
    "bvh-median", "binary BVH, object median of centroids on the longest axis", 60)};
const Registrar kRegisterSah{
    structure_info<BvhSah>("bvh-sah", "binary BVH, binned SAH (Wald 2007), parallel build", 61)};
const Registrar kRegisterSweep{
    structure_info<BvhSweep>("bvh-sweep", "binary BVH, full sweep SAH on all axes (quality reference)", 62)};
}  // namespace

}  // namespace ab
