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
#include <vector>

#include "accel/bvh/binned_split.h"
#include "accel/bvh/build.h"
#include "accel/bvh/huge_pages.h"
#include "accel/bvh/sah_split.h"
#include "accel/bvh/slots.h"
#include "accel/common/binning.h"

namespace ab {

namespace {

// Binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"): at each node the
// centroids are projected into equal-width bins on all three axes in one pass (SSE: one vector of bin
// indices and one box update per axis), every bin boundary is evaluated by a sweep over the bins, and the
// range is partitioned at the cheapest one. The partition pass also computes the children's
// centroid bounds, and their boxes are unions of bins, so no node needs a separate bounding pass. The
// partition moves references between two buffers (a node's children live in the other buffer than the
// node), so nothing is copied back per node; a leaf writes its ids to the leaf order from either buffer.
// Nodes above kParallelReduceThreshold bin in parallel and subtrees above parallel_threshold are built in
// parallel; the tree is the same for any number of threads.
class BinnedBuilder {
 public:
  BinnedBuilder(const BvhSahConfig& config, size_t n, const PrimBoundsSource& bounds);

  /// Builds the tree and returns its slots and leaf order.
  BvhSlotsResult run();

 private:
  /// The children of a split node: their bounds, the first reference of the right one and their buffer.
  struct Children {
    NodeBounds left, right;
    uint32_t m = 0;
    int buffer = 0;
  };

  uint32_t build(uint32_t p, uint32_t b, uint32_t e, const NodeBounds& nb, int depth, int buffer);
  bool split(uint32_t b, uint32_t e, const NodeBounds& nb, int buffer, Children& out);
  void make_leaf(uint32_t p, uint32_t b, uint32_t e, int buffer);
  void partition(const BinRef* refs, BinRef* out, uint32_t b, uint32_t m, uint32_t e, int axis, int position,
                 const BinMapping& map, Box4& left_c, Box4& right_c);
  NodeBounds write_refs(const PrimBoundsSource& bounds);

  const BvhSahConfig& config_;
  size_t n_;
  /// The references and the second partition buffer; uninitialized and on huge pages (huge_pages.h; every
  /// element is written before it is read).
  LargeArray<BinRef> buffers_[2];
  BvhSlots slots_;
  /// The leaf order of the ids, written by make_leaf from whichever buffer holds the leaf.
  std::vector<uint32_t> order_;
  /// The root's box and centroid box, gathered while the references are written.
  NodeBounds root_;
};

BinnedBuilder::BinnedBuilder(const BvhSahConfig& config, size_t n, const PrimBoundsSource& bounds)
    : config_(config),
      n_(n),
      buffers_{LargeArray<BinRef>(n_), LargeArray<BinRef>(n_)},
      slots_(n_),
      order_(n_) {
  root_ = write_refs(bounds);
}

/// Writes the references of all primitives into buffer 0 and returns their box and centroid box, in the
/// same pass (a parallel reduction of exact min / max, so the result does not depend on the threads).
NodeBounds BinnedBuilder::write_refs(const PrimBoundsSource& bounds) {
  BinRef* refs = buffers_[0].get();
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
  if (n_ > 0) build(0, 0, uint32_t(n_), root_, 0, 0);
  return {std::move(slots_), std::move(order_)};
}

/// A leaf over [b, e): its ids go to the leaf order from the buffer that holds them (no references are
/// copied back to one buffer, and no pass over all of them extracts the order at the end).
void BinnedBuilder::make_leaf(uint32_t p, uint32_t b, uint32_t e, int buffer) {
  slots_.set_leaf(p, b, e);
  const BinRef* refs = buffers_[buffer].get();
  for (uint32_t k = b; k < e; ++k) order_[k] = refs[k].id;
}

/// Splits [b, e) of buffers_[buffer] into children: at the cheapest bin boundary (partitioned into the
/// other buffer) or, when no split is valid but the node is too large for a leaf, in the middle of the
/// current order. Returns false when the node is a leaf.
bool BinnedBuilder::split(uint32_t b, uint32_t e, const NodeBounds& nb, int buffer, Children& out) {
  const uint32_t n = e - b;
  const BinRef* refs = buffers_[buffer].get();
  // Small nodes use as many bins as primitives (at least 4): more could not separate them better on
  // average, and evaluating unused boundaries would dominate the cost near the leaves.
  const BinMapping map(nb.centroids.aabb(), std::min(config_.bins, std::max(4, int(n))));
  const BinnedSplit found = find_binned_split(refs, b, e, nb.box, map, config_.costs);
  const uint32_t decision = sah_decision(n, found.sah, config_);
  if (decision == 0) return false;
  out.buffer = buffer;
  if (decision == n) {
    out.left.box = found.left;
    out.right.box = found.right;
    out.m = b + found.left_count;
    out.buffer = 1 - buffer;
    partition(refs, buffers_[out.buffer].get(), b, out.m, e, found.sah.axis, found.sah.position, map,
              out.left.centroids, out.right.centroids);
  } else {  // forced split in the middle of the current order
    out.m = b + decision;
    for (uint32_t k = b; k < e; ++k) {
      NodeBounds& side = k < out.m ? out.left : out.right;
      side.box.extend(refs[k].lo4(), refs[k].hi4());
      side.centroids.extend(refs[k].center(), refs[k].center());
    }
  }
  return true;
}

/// Builds the subtree of slot p over [b, e) of buffers_[buffer] and returns how many slots it takes. A node
/// whose children are built in parallel gives them the gapped slots p + 1 and p + 2 (m - b) (slots.h); below
/// parallel_threshold the subtree is laid out compactly, its right child in the slot after its left subtree,
/// so the slots it leaves free are never touched (nor zeroed by the kernel) and the passes that read the
/// slots (the collapse, the statistics walk, the flatten) read them densely. Either way the tree is the same.
uint32_t BinnedBuilder::build(uint32_t p, uint32_t b, uint32_t e, const NodeBounds& nb, int depth,
                              int buffer) {
  slots_.set_box(p, nb.box.aabb());
  const uint32_t n = e - b;
  Children c;
  if (depth >= config_.max_depth || n == 1 || leaf_without_search(n, config_) ||
      !split(b, e, nb, buffer, c)) {
    make_leaf(p, b, e, buffer);
    return 1;
  }
  if (n >= config_.parallel_threshold) {
    const uint32_t right_slot = slots_.set_interior(p, b, c.m);
    tbb::parallel_invoke([&] { build(p + 1, b, c.m, c.left, depth + 1, c.buffer); },
                         [&] { build(right_slot, c.m, e, c.right, depth + 1, c.buffer); });
    return 2 * n - 1;
  }
  const uint32_t left_slots = build(p + 1, b, c.m, c.left, depth + 1, c.buffer);
  slots_.set_right(p, p + 1 + left_slots);
  return 1 + left_slots + build(p + 1 + left_slots, c.m, e, c.right, depth + 1, c.buffer);
}

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
SideBounds partition_range(const BinRef* refs, BinRef* out, uint32_t b, uint32_t e, uint32_t l, uint32_t r,
                           const SideTest& side) {
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

/// Partitions [b, e) stably into [b, m), the primitives whose bin on `axis` lies below `position` (m - b
/// of them, known from the bins), and [m, e), from refs into out, gathering each side's centroid bounds.
/// Large ranges are cut into blocks of kGrain: one parallel pass counts each block's left references, a
/// prefix sum gives every block its two cursors, and a second parallel pass moves them (the same order as
/// the serial pass, and the bounds are exact min / max, so the result does not depend on the threads).
void BinnedBuilder::partition(const BinRef* refs, BinRef* out, uint32_t b, uint32_t m, uint32_t e, int axis,
                              int position, const BinMapping& map, Box4& left_c, Box4& right_c) {
  const SideTest side(map, axis, position);
  if (e - b < kParallelReduceThreshold) {
    const SideBounds s = partition_range(refs, out, b, e, b, m, side);
    return left_c.extend(s.left), right_c.extend(s.right);
  }
  const size_t blocks = (e - b + kGrain - 1) / kGrain;
  auto block_end = [&](size_t i) { return uint32_t(std::min<size_t>(e, b + (i + 1) * kGrain)); };
  std::vector<uint32_t> lefts(blocks + 1, 0);
  tbb::parallel_for(size_t(0), blocks, [&](size_t i) {
    uint32_t n = 0;
    for (uint32_t k = uint32_t(b + i * kGrain), end = block_end(i); k < end; ++k) n += side.left(refs[k]);
    lefts[i + 1] = n;
  });
  for (size_t i = 0; i < blocks; ++i) lefts[i + 1] += lefts[i];
  std::vector<SideBounds> bounds(blocks);
  tbb::parallel_for(size_t(0), blocks, [&](size_t i) {
    const uint32_t first = uint32_t(b + i * kGrain);
    bounds[i] =
        partition_range(refs, out, first, block_end(i), b + lefts[i], m + (first - b - lefts[i]), side);
  });
  for (const SideBounds& s : bounds) left_c.extend(s.left), right_c.extend(s.right);
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
