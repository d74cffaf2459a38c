// The object-median BVH builder (bvh-median).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>

#include "accel/bvh/build.h"
#include "accel/bvh/slots.h"

namespace ab {

namespace {

/// Ranges at least this large compute their bounds with a parallel reduction (min and max only: exact,
/// so the result does not depend on the split).
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

/// A primitive as the median builder moves it around: bounds, centroid and id together, so the passes
/// over a range read contiguous memory.
struct BuildRef {
  AABB box;
  vec3 centroid;
  uint32_t id;
};

// Object median (pbrt's EqualCounts split; Pharr, Jakob and Humphreys, "Physically Based Rendering"):
// recursion over ranges of the reference array; each node is split at the median centroid along the
// longest axis of its centroid bounds (sort-free selection with nth_element), ties broken by id
// so the result is a function of the range alone. Large subtrees are built in parallel into BvhSlots.
class MedianBuilder {
 public:
  MedianBuilder(const BvhMedianConfig& config, std::span<const AABB> bounds, std::span<const vec3> centroids)
      : config_(config), refs_(bounds.size()), slots_(bounds.size()) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, refs_.size(), kGrain),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i < r.end(); ++i)
                          refs_[i] = {bounds[i], centroids[i], uint32_t(i)};
                      });
  }

  /// Builds the tree and returns the flattened result.
  BvhBuildResult run() {
    if (!refs_.empty()) build(0, 0, uint32_t(refs_.size()), 0);
    std::vector<uint32_t> order(refs_.size());
    for (size_t k = 0; k < refs_.size(); ++k) order[k] = refs_[k].id;
    return flatten_bvh_slots(slots_, std::move(order));
  }

 private:
  void build(uint32_t p, uint32_t b, uint32_t e, int depth);
  RangeBounds range_bounds(uint32_t b, uint32_t e) const;
  uint32_t split_median(uint32_t b, uint32_t e, const RangeBounds& rb);

  const BvhMedianConfig& config_;
  std::vector<BuildRef> refs_;
  BvhSlots slots_;
};

void MedianBuilder::build(uint32_t p, uint32_t b, uint32_t e, int depth) {
  const RangeBounds rb = range_bounds(b, e);
  slots_.set_box(p, rb.bounds);
  const uint32_t m = depth >= config_.max_depth ? b : split_median(b, e, rb);
  if (m == b) return slots_.set_leaf(p, b, e);
  const uint32_t right = slots_.set_interior(p, b, m);
  if (e - b >= config_.parallel_threshold) {
    tbb::parallel_invoke([&] { build(p + 1, b, m, depth + 1); }, [&] { build(right, m, e, depth + 1); });
  } else {
    build(p + 1, b, m, depth + 1);
    build(right, m, e, depth + 1);
  }
}

RangeBounds MedianBuilder::range_bounds(uint32_t b, uint32_t e) const {
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
uint32_t MedianBuilder::split_median(uint32_t b, uint32_t e, const RangeBounds& rb) {
  const uint32_t n = e - b;
  if (n <= uint32_t(config_.leaf_size)) return b;
  const int axis = rb.centroids.longest_axis();
  const uint32_t m = b + n / 2;
  if (!(rb.centroids.extent()[axis] > 0.0f)) return m;  // all centroids coincide: split by position
  std::nth_element(refs_.begin() + b, refs_.begin() + m, refs_.begin() + e,
                   [&](const BuildRef& x, const BuildRef& y) {
                     const float cx = x.centroid[axis], cy = y.centroid[axis];
                     return cx != cy ? cx < cy : x.id < y.id;
                   });
  return m;
}

}  // namespace

BvhBuildResult build_bvh(const BvhMedianConfig& config, std::span<const AABB> bounds,
                         std::span<const vec3> centroids) {
  return MedianBuilder(config, bounds, centroids).run();
}

}  // namespace ab
