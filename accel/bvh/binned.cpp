// The binned SAH BVH builder (bvh-sah).
#include <immintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <bit>
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

#include "accel/bvh/binned_split.h"
#include "accel/bvh/build.h"
#include "accel/bvh/sah_split.h"
#include "accel/bvh/slots.h"
#include "accel/common/binning.h"
#include "accel/common/huge_pages.h"

namespace ab {

namespace {

// Binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"): at each node the
// centroids are projected into equal-width bins on all three axes in one pass (SSE: one vector of bin
// indices and one box update per axis), every bin boundary is evaluated by a sweep over the bins, and the
// range is partitioned at the cheapest one. The partition pass also computes the children's
// centroid bounds, and their boxes are unions of bins, so no node needs a separate bounding pass. Nodes of
// at least kParallelReduceThreshold references bin in parallel and are partitioned in place in the one
// reference array, in parallel (partition_in_place). Below that, a subtree gets a scratch buffer of its
// size, and its partitions move references between the array and the scratch (a node's children live in
// the other buffer than the node), so nothing is copied back per node; a leaf writes its ids to the leaf
// order from either buffer. Subtrees above parallel_threshold are built in parallel; the tree and the
// leaf order are the same for any number of threads.
/// References partitioned at once, through a buffer on the stack, by the in-place partition.
constexpr uint32_t kPartitionBlock = 1024;

class BinnedBuilder {
 public:
  BinnedBuilder(const BvhSahConfig& config, size_t n, const PrimBoundsSource& bounds);

  /// Builds the tree and returns its slots and leaf order.
  BvhSlotsResult run();

 private:
  /// The children of a split node: their bounds, the first reference of the right one, and whether they
  /// were moved into the node's spare buffer.
  struct Children {
    NodeBounds left, right;
    uint32_t m = 0;
    bool moved = false;
  };

  uint32_t build(uint32_t p, uint32_t b, uint32_t e, const NodeBounds& nb, int depth, BinRef* refs,
                 BinRef* spare);
  bool split(uint32_t b, uint32_t e, const NodeBounds& nb, BinRef* refs, BinRef* spare, Children& out);
  void make_leaf(uint32_t p, uint32_t b, uint32_t e, const BinRef* refs);
  NodeBounds write_refs(const PrimBoundsSource& bounds);

  const BvhSahConfig& config_;
  size_t n_;
  /// The references; uninitialized and on huge pages (huge_pages.h; every element is written before it is
  /// read).
  LargeArray<BinRef> refs_;
  BvhSlots slots_;
  /// The leaf order of the ids, written by make_leaf from whichever buffer holds the leaf.
  std::vector<uint32_t> order_;
  /// The root's box and centroid box, gathered while the references are written.
  NodeBounds root_;
};

/// Which side of the split a reference goes to: its bin on the split's axis below the split's position, with
/// the binning's own vector arithmetic (BinIndexer) on its centre, so bit for bit the bin it was counted in.
/// The centre is the one the partition also folds into the sides' centroid bounds.
struct SideTest {
  BinIndexer ix;
  __m128i position;
  int axis_bit;

  SideTest(const BinMapping& map, int a, int pos)
      : ix(map), position(_mm_set1_epi32(pos)), axis_bit(1 << a) {}
  bool left(__m128 center) const {
    const __m128i below = _mm_cmplt_epi32(ix.bins(center), position);
    return (_mm_movemask_ps(_mm_castsi128_ps(below)) & axis_bit) != 0;
  }
  bool left(const BinRef& ref) const { return left(ref.center()); }
};

/// The centroid bounds of both sides of a partition.
struct SideBounds {
  Box4 left = Box4::empty(), right = Box4::empty();
};

/// Moves refs [b, e) into out, the left ones from cursor l on and the others from cursor r on, in order,
/// and returns both sides' centroid bounds. Branch-free: each reference is written at the cursor of its
/// side (a conditional move, not a mispredicted branch); the bounds are kept in registers.
[[gnu::noinline]] SideBounds partition_range(const BinRef* refs, BinRef* out, uint32_t b, uint32_t e,
                                             uint32_t l, uint32_t r, const SideTest& side) {
  const __m128 inf = _mm_set1_ps(kInf), minus_inf = _mm_set1_ps(-kInf);
  Box4 lc = Box4::empty(), rc = Box4::empty();
  for (uint32_t k = b; k < e; ++k) {
    const BinRef& ref = refs[k];
    const __m128 c = ref.center();
    const bool left = side.left(c);
    out[left ? l : r] = ref;
    l += left;
    r += !left;
    const __m128 mask = _mm_castsi128_ps(_mm_set1_epi32(-int(left)));
    lc.extend(_mm_blendv_ps(inf, c, mask), _mm_blendv_ps(minus_inf, c, mask));
    rc.extend(_mm_blendv_ps(c, inf, mask), _mm_blendv_ps(c, minus_inf, mask));
  }
  return {lc, rc};
}

/// Partitions the block refs[0, n) in place through tmp (n <= kPartitionBlock): the left references to the
/// front in order, the others behind them in reverse order. Returns the number of left ones and both sides'
/// centroid bounds.
[[gnu::noinline]] std::pair<uint32_t, SideBounds> partition_block(BinRef* refs, uint32_t n,
                                                                  const SideTest& side, BinRef* tmp) {
  const __m128 inf = _mm_set1_ps(kInf), minus_inf = _mm_set1_ps(-kInf);
  Box4 lc = Box4::empty(), rc = Box4::empty();
  uint32_t l = 0, r = n - 1;
  for (uint32_t k = 0; k < n; ++k) {
    const BinRef& ref = refs[k];
    const __m128 c = ref.center();
    const bool left = side.left(c);
    tmp[left ? l : r] = ref;
    l += left;
    r -= !left;
    const __m128 mask = _mm_castsi128_ps(_mm_set1_epi32(-int(left)));
    lc.extend(_mm_blendv_ps(inf, c, mask), _mm_blendv_ps(minus_inf, c, mask));
    rc.extend(_mm_blendv_ps(c, inf, mask), _mm_blendv_ps(c, minus_inf, mask));
  }
  std::copy(tmp, tmp + n, refs);
  return {l, {lc, rc}};
}

/// A run of references [first, first + size) of one block that lie on the wrong side of the partition.
struct Run {
  uint32_t first, size;
};

/// Swaps the k-th misplaced reference of `rights` with the k-th of `lefts` for k in [k0, k1); the runs'
/// prefix sums (`*_end`: references up to and including each run) locate the k0-th of each.
void swap_misplaced(BinRef* refs, const std::vector<Run>& rights, const std::vector<uint32_t>& rights_end,
                    const std::vector<Run>& lefts, const std::vector<uint32_t>& lefts_end, uint32_t k0,
                    uint32_t k1) {
  size_t i = size_t(std::upper_bound(rights_end.begin(), rights_end.end(), k0) - rights_end.begin());
  size_t j = size_t(std::upper_bound(lefts_end.begin(), lefts_end.end(), k0) - lefts_end.begin());
  uint32_t a = rights[i].first + (k0 - (rights_end[i] - rights[i].size));
  uint32_t c = lefts[j].first + (k0 - (lefts_end[j] - lefts[j].size));
  for (uint32_t k = k0; k < k1; ++k) {
    if (a == rights[i].first + rights[i].size) a = rights[++i].first;
    if (c == lefts[j].first + lefts[j].size) c = lefts[++j].first;
    std::swap(refs[a++], refs[c++]);
  }
}

/// Partitions refs[0, n) in place so that the nl references whose bin lies below the split come first,
/// and returns both sides' centroid bounds (Wald 2007's partition, done in place in parallel as in Embree's
/// parallel_partition, here with fixed blocks so that the order does not depend on the threads): each block
/// of kPartitionBlock is partitioned on its own, in parallel; then the right references that lie before nl
/// are swapped with the left ones that lie after it, the k-th with the k-th, in parallel chunks. Exact min
/// / max bounds, so the result does not depend on the threads either.
SideBounds partition_in_place(BinRef* refs, uint32_t n, uint32_t nl, const SideTest& side) {
  const size_t blocks = (n + kPartitionBlock - 1) / kPartitionBlock;
  std::vector<uint32_t> lefts(blocks);
  std::vector<SideBounds> bounds(blocks);
  tbb::parallel_for(size_t(0), blocks, [&](size_t i) {
    alignas(32) BinRef tmp[kPartitionBlock];
    const uint32_t first = uint32_t(i * kPartitionBlock);
    const uint32_t size = std::min(n - first, uint32_t(kPartitionBlock));
    std::tie(lefts[i], bounds[i]) = partition_block(refs + first, size, side, tmp);
  });
  SideBounds all;
  std::vector<Run> rights_before, lefts_after;  // the misplaced runs, in position order
  for (size_t i = 0; i < blocks; ++i) {
    all.left.extend(bounds[i].left);
    all.right.extend(bounds[i].right);
    const uint32_t first = uint32_t(i * kPartitionBlock), mid = first + lefts[i];
    const uint32_t last = std::min(n, first + uint32_t(kPartitionBlock));
    if (mid < std::min(last, nl)) rights_before.push_back({mid, std::min(last, nl) - mid});
    if (std::max(first, nl) < mid) lefts_after.push_back({std::max(first, nl), mid - std::max(first, nl)});
  }
  auto ends = [](const std::vector<Run>& runs) {
    std::vector<uint32_t> end(runs.size());
    for (size_t i = 0, sum = 0; i < runs.size(); ++i) end[i] = uint32_t(sum += runs[i].size);
    return end;
  };
  const std::vector<uint32_t> rights_end = ends(rights_before), lefts_end = ends(lefts_after);
  const uint32_t misplaced = rights_end.empty() ? 0 : rights_end.back();
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, misplaced, kPartitionBlock),
                    [&](const tbb::blocked_range<uint32_t>& r) {
                      swap_misplaced(refs, rights_before, rights_end, lefts_after, lefts_end, r.begin(),
                                     r.end());
                    });
  return all;
}

BinnedBuilder::BinnedBuilder(const BvhSahConfig& config, size_t n, const PrimBoundsSource& bounds)
    : config_(config), n_(n), refs_(n_), slots_(n_), order_(n_) {
  root_ = write_refs(bounds);
}

/// Writes the references of all primitives and returns their box and centroid box, in the
/// same pass (a parallel reduction of exact min / max, so the result does not depend on the threads).
NodeBounds BinnedBuilder::write_refs(const PrimBoundsSource& bounds) {
  BinRef* refs = refs_.get();
  auto body = [&](const tbb::blocked_range<size_t>& r, NodeBounds acc) {
    AABB box[kBoundsBlock];  // a range may be longer than its grain: it is read block by block
    for (size_t first = r.begin(); first < r.end(); first += kBoundsBlock) {
      const size_t last = std::min(r.end(), first + kBoundsBlock);
      bounds(first, last, box);
      for (size_t i = first; i < last; ++i) {
        const AABB& b = box[i - first];
        refs[i] = {{b.lo.x, b.lo.y, b.lo.z}, uint32_t(i), {b.hi.x, b.hi.y, b.hi.z}, 0.0f};
        acc.box.extend(refs[i].lo4(), refs[i].hi4());
        const __m128 c = refs[i].center();
        acc.centroids.extend(c, c);
      }
    }
    return acc;
  };
  return tbb::parallel_reduce(tbb::blocked_range<size_t>(0, n_, kGrain), NodeBounds{}, body,
                              [](NodeBounds x, const NodeBounds& y) {
                                x.box.extend(y.box);
                                x.centroids.extend(y.centroids);
                                return x;
                              });
}

BvhSlotsResult BinnedBuilder::run() {
  if (n_ > 0) build(0, 0, uint32_t(n_), root_, 0, refs_.get(), nullptr);
  return {std::move(slots_), std::move(order_)};
}

/// A leaf over [b, e), whose references start at refs: its ids go to the leaf order from the buffer that
/// holds them (no references are copied back to one buffer, and no pass over all of them extracts the order
/// at the end).
void BinnedBuilder::make_leaf(uint32_t p, uint32_t b, uint32_t e, const BinRef* refs) {
  slots_.set_leaf(p, b, e);
  for (uint32_t k = b; k < e; ++k) order_[k] = refs[k - b].id;
}

/// Splits [b, e), whose references start at refs, into children: at the cheapest bin boundary (partitioned
/// into `spare`, or in place when there is no spare buffer) or, when no split is valid but the node is too
/// large for a leaf, in the middle of the current order. Returns false when the node is a leaf.
bool BinnedBuilder::split(uint32_t b, uint32_t e, const NodeBounds& nb, BinRef* refs, BinRef* spare,
                          Children& out) {
  const uint32_t n = e - b;
  // Small nodes use as many bins as primitives (at least 4): more could not separate them better on
  // average, and evaluating unused boundaries would dominate the cost near the leaves.
  const BinMapping map(nb.centroids.aabb(), std::min(config_.bins, std::max(4, int(n))));
  const BinnedSplit found = find_binned_split(refs, 0, n, nb.box, map, config_.costs);
  const uint32_t decision = sah_decision(n, found.sah, config_);
  if (decision == 0) return false;
  if (decision == n) {
    out.left.box = found.left;
    out.right.box = found.right;
    out.m = b + found.left_count;
    const SideTest side(map, found.sah.axis, found.sah.position);
    const SideBounds s = spare ? partition_range(refs, spare, 0, n, 0, found.left_count, side)
                               : partition_in_place(refs, n, found.left_count, side);
    out.left.centroids = s.left;
    out.right.centroids = s.right;
    out.moved = spare != nullptr;
  } else {  // forced split in the middle of the current order
    out.m = b + decision;
    for (uint32_t k = 0; k < n; ++k) {
      NodeBounds& side = k < decision ? out.left : out.right;
      side.box.extend(refs[k].lo4(), refs[k].hi4());
      side.centroids.extend(refs[k].center(), refs[k].center());
    }
  }
  return true;
}

/// Builds the subtree of slot p over [b, e), whose references start at refs (with `spare`, the same range
/// of the other buffer, or null above kParallelReduceThreshold), and returns how many slots it takes. A
/// node whose children are built in parallel gives them the gapped slots p + 1 and p + 2 (m - b)
/// (slots.h); below parallel_threshold the subtree is laid out compactly, its right child in the slot after
/// its left subtree, so the slots it leaves free are never touched (nor zeroed by the kernel) and the passes
/// that read the slots (the collapse, the statistics walk, the flatten) read them densely. Either way the
/// tree is the same.
uint32_t BinnedBuilder::build(uint32_t p, uint32_t b, uint32_t e, const NodeBounds& nb, int depth,
                              BinRef* refs, BinRef* spare) {
  slots_.set_box(p, nb.box.aabb());
  const uint32_t n = e - b;
  if (depth >= config_.max_depth || n == 1 || leaf_without_search(n, config_)) {
    make_leaf(p, b, e, refs);
    return 1;
  }
  std::unique_ptr<BinRef[]> scratch;  // the spare buffer of a subtree below the in-place partitions
  if (spare == nullptr && n < kParallelReduceThreshold) {
    scratch = std::make_unique_for_overwrite<BinRef[]>(n);
    spare = scratch.get();
  }
  Children c;
  if (!split(b, e, nb, refs, spare, c)) {
    make_leaf(p, b, e, refs);
    return 1;
  }
  if (c.moved) std::swap(refs, spare);
  BinRef* right_refs = refs + (c.m - b);
  BinRef* right_spare = spare ? spare + (c.m - b) : nullptr;
  if (n >= config_.parallel_threshold) {
    const uint32_t right_slot = slots_.set_interior(p, b, c.m);
    tbb::parallel_invoke([&] { build(p + 1, b, c.m, c.left, depth + 1, refs, spare); },
                         [&] { build(right_slot, c.m, e, c.right, depth + 1, right_refs, right_spare); });
    return 2 * n - 1;
  }
  const uint32_t left_slots = build(p + 1, b, c.m, c.left, depth + 1, refs, spare);
  slots_.set_right(p, p + 1 + left_slots);
  return 1 + left_slots + build(p + 1 + left_slots, c.m, e, c.right, depth + 1, right_refs, right_spare);
}

}  // namespace

BvhSlotsResult build_bvh_slots(const BvhSahConfig& config, size_t n, const PrimBoundsSource& bounds) {
  return BinnedBuilder(config, n, bounds).run();
}

BvhSlotsResult build_bvh_slots(const BvhSahConfig& config, std::span<const AABB> bounds) {
  return build_bvh_slots(config, bounds.size(), [&](size_t begin, size_t end, AABB* out) {
    std::copy(bounds.begin() + begin, bounds.begin() + end, out);
  });
}

BvhBuildResult build_bvh(const BvhSahConfig& config, std::span<const AABB> bounds, std::span<const vec3>) {
  BvhSlotsResult built = build_bvh_slots(config, bounds);
  return flatten_bvh_slots(built.slots, std::move(built.order));
}

}  // namespace ab
