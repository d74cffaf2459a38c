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

#include "accel/bvh/build.h"
#include "accel/bvh/sah_split.h"
#include "accel/bvh/slots.h"
#include "accel/common/binning.h"

namespace ab {

namespace {

/// Nodes at least this large bin and bound their primitives with a parallel reduction. The reductions use
/// only min, max and integer sums, which are exact, so the result does not depend on how TBB splits.
constexpr size_t kParallelReduceThreshold = 1u << 15;
constexpr size_t kGrain = 1u << 12;
constexpr int kMaxBins = 256;

/// A primitive as the binned builder moves it: its box as two 16-byte vectors, the id in the lo vector's
/// fourth lane and zero in the hi vector's. lo4() blends the id out, so no arithmetic ever sees its bits
/// (small ids read as float are denormals, which can cost a microcode assist per operation).
struct alignas(32) BinRef {
  float lo[3];
  uint32_t id;
  float hi[3];
  float zero;

  __m128 lo4() const { return _mm_blend_ps(_mm_load_ps(lo), _mm_setzero_ps(), 8); }
  __m128 hi4() const { return _mm_load_ps(hi); }
  /// The centre of the box, 0.5 * (lo + hi), bit for bit what AABB::center() and the primitive sets'
  /// centroid() give (fourth lane 0).
  __m128 center() const { return _mm_mul_ps(_mm_add_ps(lo4(), hi4()), _mm_set1_ps(0.5f)); }
};
static_assert(sizeof(BinRef) == 32);

/// A box as two vectors. Not initialized by default (bins are reset explicitly, only as many as used).
struct alignas(16) Box4 {
  __m128 lo;
  __m128 hi;

  /// The empty box (lo = +inf, hi = -inf).
  static Box4 empty() { return {_mm_set1_ps(kInf), _mm_set1_ps(-kInf)}; }
  void extend(__m128 l, __m128 h) {
    lo = _mm_min_ps(lo, l);
    hi = _mm_max_ps(hi, h);
  }
  void extend(const Box4& b) { extend(b.lo, b.hi); }
  /// The same value as AABB::area() of the same box, 2 (dx dy + dy dz + dz dx) with the same rounding, and
  /// 0 when empty (the extent is clamped at 0 instead of branching).
  float area() const {
    const __m128 d = _mm_max_ps(_mm_sub_ps(hi, lo), _mm_setzero_ps());
    const __m128 p = _mm_mul_ps(d, _mm_shuffle_ps(d, d, _MM_SHUFFLE(3, 0, 2, 1)));  // dx dy, dy dz, dz dx
    const __m128 s = _mm_add_ss(_mm_add_ss(p, _mm_shuffle_ps(p, p, 1)), _mm_shuffle_ps(p, p, 2));
    return 2.0f * _mm_cvtss_f32(s);
  }
  AABB aabb() const {
    alignas(16) float l[4], h[4];
    _mm_store_ps(l, lo);
    _mm_store_ps(h, hi);
    return {{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
  }
};

/// The node's box and the box of its primitives' centroids, passed from a parent to its children.
struct NodeBounds {
  Box4 box = Box4::empty();
  Box4 centroids = Box4::empty();
};

/// The bin of a centre on all three axes at once: int((c - lo) * scale) clamped to [0, bins - 1], the
/// arithmetic of BinMapping::bin (binning.h) in one vector.
struct BinIndexer {
  __m128 lo, scale;
  __m128i last;

  explicit BinIndexer(const BinMapping& m)
      : lo(_mm_setr_ps(m.lo[0], m.lo[1], m.lo[2], 0.0f)),
        scale(_mm_setr_ps(m.scale[0], m.scale[1], m.scale[2], 0.0f)),
        last(_mm_set1_epi32(m.bins - 1)) {}
  __m128i bins(__m128 c) const {
    const __m128i k = _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(c, lo), scale));
    return _mm_min_epi32(_mm_max_epi32(k, _mm_setzero_si128()), last);
  }
};

/// The bins of one node on the three axes (axis a, bin k at a * nb + k), reducible in parallel.
struct BinSet {
  int nb;
  std::array<Box4, 3 * kMaxBins> box;
  std::array<uint32_t, 3 * kMaxBins> count;

  explicit BinSet(int bins) : nb(bins) {
    for (int k = 0; k < 3 * nb; ++k) box[k] = Box4::empty(), count[k] = 0;
  }
  void add(const BinRef* refs, uint32_t b, uint32_t e, const BinIndexer& ix) {
    for (uint32_t k = b; k < e; ++k) {
      const __m128 lo = refs[k].lo4(), hi = refs[k].hi4();
      alignas(16) int32_t bin[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(bin), ix.bins(refs[k].center()));
      for (int a = 0; a < 3; ++a) {
        const int j = a * nb + bin[a];
        box[j].extend(lo, hi);
        ++count[j];
      }
    }
  }
  void merge(const BinSet& o) {
    for (int k = 0; k < 3 * nb; ++k) box[k].extend(o.box[k]), count[k] += o.count[k];
  }
};

/// Areas of three boxes at once (lane a: box a), each bit for bit AABB::area() (same products, same order).
__m128 areas3(const Box4* box) {
  __m128 x = _mm_max_ps(_mm_sub_ps(box[0].hi, box[0].lo), _mm_setzero_ps());
  __m128 y = _mm_max_ps(_mm_sub_ps(box[1].hi, box[1].lo), _mm_setzero_ps());
  __m128 z = _mm_max_ps(_mm_sub_ps(box[2].hi, box[2].lo), _mm_setzero_ps());
  __m128 w = _mm_setzero_ps();
  _MM_TRANSPOSE4_PS(x, y, z, w);  // now x, y, z hold the extents along x, y, z of the three boxes
  const __m128 s = _mm_add_ps(_mm_add_ps(_mm_mul_ps(x, y), _mm_mul_ps(y, z)), _mm_mul_ps(z, x));
  return _mm_mul_ps(_mm_set1_ps(2.0f), s);
}

/// The cheapest bin boundary over the three axes, one axis per vector lane (Wald 2007): suffix areas right to
/// left, then prefix areas left to right. Within an axis a boundary is ranked by left_area * left_count +
/// right_area * right_count (the cost without its constant terms, so no division per boundary); the first
/// cheapest boundary of each axis is priced with SahCosts::split, and the first cheapest axis wins. Axes
/// whose lane in `axis_ok` is clear (flat centroid extent) are skipped.
SahSplit best_split_three_axes(const BinSet& bins, __m128 axis_ok, float parent_area, const SahCosts& costs) {
  const int n = bins.nb;
  auto counts = [&](int k) {
    return _mm_setr_epi32(int(bins.count[k]), int(bins.count[n + k]), int(bins.count[2 * n + k]), 0);
  };
  auto extend = [&](Box4* acc, int k) {
    for (int a = 0; a < 3; ++a) acc[a].extend(bins.box[a * n + k]);
  };
  __m128 right_area[kMaxBins];  // only [1, n) is written and read
  __m128i right_count[kMaxBins];
  Box4 acc[3] = {Box4::empty(), Box4::empty(), Box4::empty()};
  __m128i cnt = _mm_setzero_si128();
  for (int i = n - 1; i > 0; --i) {
    extend(acc, i);
    cnt = _mm_add_epi32(cnt, counts(i));
    right_area[i] = areas3(acc);
    right_count[i] = cnt;
  }
  acc[0] = acc[1] = acc[2] = Box4::empty();
  cnt = _mm_setzero_si128();
  __m128 best_w = _mm_set1_ps(kInf), best_la = _mm_setzero_ps(), best_ra = _mm_setzero_ps();
  __m128i best_i = _mm_setzero_si128(), best_lc = _mm_setzero_si128();
  for (int i = 1; i < n; ++i) {
    extend(acc, i - 1);
    cnt = _mm_add_epi32(cnt, counts(i - 1));
    const __m128 la = areas3(acc), ra = right_area[i];
    const __m128 w =
        _mm_add_ps(_mm_mul_ps(la, _mm_cvtepi32_ps(cnt)), _mm_mul_ps(ra, _mm_cvtepi32_ps(right_count[i])));
    const __m128i empty_side = _mm_or_si128(_mm_cmpeq_epi32(cnt, _mm_setzero_si128()),
                                            _mm_cmpeq_epi32(right_count[i], _mm_setzero_si128()));
    const __m128 better =
        _mm_andnot_ps(_mm_castsi128_ps(empty_side), _mm_and_ps(axis_ok, _mm_cmplt_ps(w, best_w)));
    best_w = _mm_blendv_ps(best_w, w, better);
    best_la = _mm_blendv_ps(best_la, la, better);
    best_ra = _mm_blendv_ps(best_ra, ra, better);
    best_i = _mm_castps_si128(
        _mm_blendv_ps(_mm_castsi128_ps(best_i), _mm_castsi128_ps(_mm_set1_epi32(i)), better));
    best_lc = _mm_castps_si128(_mm_blendv_ps(_mm_castsi128_ps(best_lc), _mm_castsi128_ps(cnt), better));
  }
  alignas(16) int32_t bi[4], lc[4], total[4];
  alignas(16) float bla[4], bra[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(bi), best_i);
  _mm_store_si128(reinterpret_cast<__m128i*>(lc), best_lc);
  _mm_store_si128(reinterpret_cast<__m128i*>(total), _mm_add_epi32(cnt, counts(n - 1)));
  _mm_store_ps(bla, best_la);
  _mm_store_ps(bra, best_ra);
  SahSplit best;
  for (int a = 0; a < 3; ++a) {
    if (bi[a] == 0) continue;
    const float c = costs.split(parent_area, bla[a], uint32_t(lc[a]), bra[a], uint32_t(total[a] - lc[a]));
    if (c < best.cost) best = {a, bi[a], c};
  }
  return best;
}

/// TBB body binning a large range in parallel (the imperative form: a BinSet is copied only when a
/// subrange is stolen).
struct ParallelBinning {
  const BinRef* refs;
  const BinIndexer& ix;
  BinSet bins;

  ParallelBinning(const BinRef* r, const BinIndexer& i, int nb) : refs(r), ix(i), bins(nb) {}
  ParallelBinning(ParallelBinning& o, tbb::split) : refs(o.refs), ix(o.ix), bins(o.bins.nb) {}
  void operator()(const tbb::blocked_range<uint32_t>& r) { bins.add(refs, r.begin(), r.end(), ix); }
  void join(const ParallelBinning& o) { bins.merge(o.bins); }
};

/// The chosen split of a node: SahSplit plus the children's boxes (unions of bins).
struct BinnedSplit {
  SahSplit sah;
  Box4 left = Box4::empty(), right = Box4::empty();
  uint32_t left_count = 0;
};

// Binned SAH (Wald 2007, "On fast construction of SAH-based bounding volume hierarchies"): at each node the
// centroids are projected into equal-width bins on all three axes in one pass (SSE: one vector of bin
// indices and one box update per axis), every bin boundary is evaluated by a sweep over the bins, and the
// range is partitioned at the cheapest one. The partition pass also computes the children's
// centroid bounds, and their boxes are unions of bins, so no node needs a separate bounding pass. The
// partition moves references between two buffers (a node's children live in the other buffer than the
// node; a leaf left in the second buffer is copied back), so nothing is copied back per node. Nodes
// above kParallelReduceThreshold bin in parallel and subtrees above parallel_threshold are built in
// parallel; the tree is the same for any number of threads.
class BinnedBuilder {
 public:
  BinnedBuilder(const BvhSahConfig& config, std::span<const AABB> bounds);

  /// Builds the tree and returns the flattened result.
  BvhBuildResult run();

 private:
  void build(uint32_t p, uint32_t b, uint32_t e, const NodeBounds& nb, int depth, int buffer);
  void make_leaf(uint32_t p, uint32_t b, uint32_t e, int buffer);
  BinnedSplit find_split(const BinRef* refs, uint32_t b, uint32_t e, const NodeBounds& nb,
                         const BinMapping& map) const;
  void partition(const BinRef* refs, BinRef* out, uint32_t b, uint32_t m, uint32_t e, int axis, int position,
                 const BinMapping& map, Box4& left_c, Box4& right_c);
  NodeBounds root_bounds() const;

  const BvhSahConfig& config_;
  size_t n_;
  /// The references (buffer 0, which holds the final leaf order) and the second partition buffer;
  /// uninitialized allocations (every element is written before it is read).
  std::unique_ptr<BinRef[]> buffers_[2];
  BvhSlots slots_;
};

BinnedBuilder::BinnedBuilder(const BvhSahConfig& config, std::span<const AABB> bounds)
    : config_(config),
      n_(bounds.size()),
      buffers_{std::make_unique_for_overwrite<BinRef[]>(n_), std::make_unique_for_overwrite<BinRef[]>(n_)},
      slots_(n_) {
  BinRef* refs = buffers_[0].get();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n_, kGrain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const AABB& b = bounds[i];
      refs[i] = {{b.lo.x, b.lo.y, b.lo.z}, uint32_t(i), {b.hi.x, b.hi.y, b.hi.z}, 0.0f};
    }
  });
}

BvhBuildResult BinnedBuilder::run() {
  const size_t n = n_;
  if (n > 0) build(0, 0, uint32_t(n), root_bounds(), 0, 0);
  std::vector<uint32_t> order(n);
  const BinRef* refs = buffers_[0].get();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kGrain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) order[k] = refs[k].id;
  });
  return flatten_bvh_slots(slots_, std::move(order));
}

NodeBounds BinnedBuilder::root_bounds() const {
  const BinRef* refs = buffers_[0].get();
  auto body = [&](const tbb::blocked_range<size_t>& r, NodeBounds acc) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      acc.box.extend(refs[k].lo4(), refs[k].hi4());
      const __m128 c = refs[k].center();
      acc.centroids.extend(c, c);
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

/// A leaf over [b, e); its references are moved to buffer 0 if they are in buffer 1.
void BinnedBuilder::make_leaf(uint32_t p, uint32_t b, uint32_t e, int buffer) {
  slots_.set_leaf(p, b, e);
  if (buffer == 1) std::copy(buffers_[1].get() + b, buffers_[1].get() + e, buffers_[0].get() + b);
}

/// Builds the subtree of slot p over [b, e) of buffers_[buffer].
void BinnedBuilder::build(uint32_t p, uint32_t b, uint32_t e, const NodeBounds& nb, int depth, int buffer) {
  const AABB box = nb.box.aabb();
  slots_.set_box(p, box);
  const uint32_t n = e - b;
  if (depth >= config_.max_depth || n == 1) return make_leaf(p, b, e, buffer);
  const BinRef* refs = buffers_[buffer].get();
  // Small nodes use as many bins as primitives (at least 4): more could not separate them better on
  // average, and evaluating unused boundaries would dominate the cost near the leaves.
  const BinMapping map(nb.centroids.aabb(), std::min(config_.bins, std::max(4, int(n))));
  const BinnedSplit split = find_split(refs, b, e, nb, map);
  const uint32_t decision = sah_decision(n, split.sah, config_);
  if (decision == 0) return make_leaf(p, b, e, buffer);
  NodeBounds left, right;
  uint32_t m;
  int child_buffer = buffer;
  if (decision == n) {
    left.box = split.left;
    right.box = split.right;
    m = b + split.left_count;
    child_buffer = 1 - buffer;
    partition(refs, buffers_[child_buffer].get(), b, m, e, split.sah.axis, split.sah.position, map,
              left.centroids, right.centroids);
  } else {  // forced split in the middle of the current order
    m = b + decision;
    for (uint32_t k = b; k < e; ++k) {
      NodeBounds& side = k < m ? left : right;
      side.box.extend(refs[k].lo4(), refs[k].hi4());
      side.centroids.extend(refs[k].center(), refs[k].center());
    }
  }
  const uint32_t right_slot = slots_.set_interior(p, b, m);
  auto build_left = [&] { build(p + 1, b, m, left, depth + 1, child_buffer); };
  auto build_right = [&] { build(right_slot, m, e, right, depth + 1, child_buffer); };
  if (n >= config_.parallel_threshold) {
    tbb::parallel_invoke(build_left, build_right);
  } else {
    build_left();
    build_right();
  }
}

/// Bins the node with `map` and finds the cheapest bin boundary over the three axes.
BinnedSplit BinnedBuilder::find_split(const BinRef* refs, uint32_t b, uint32_t e, const NodeBounds& nb,
                                      const BinMapping& map) const {
  const BinIndexer ix(map);
  BinnedSplit out;
  auto evaluate = [&](const BinSet& bins) {
    const __m128 axis_ok =
        _mm_cmpgt_ps(_mm_setr_ps(map.scale[0], map.scale[1], map.scale[2], 0.0f), _mm_setzero_ps());
    out.sah = best_split_three_axes(bins, axis_ok, nb.box.area(), config_.costs);
    if (out.sah.axis < 0) return;
    const int base = out.sah.axis * bins.nb;
    for (int k = 0; k < bins.nb; ++k) {
      (k < out.sah.position ? out.left : out.right).extend(bins.box[base + k]);
      if (k < out.sah.position) out.left_count += bins.count[base + k];
    }
  };
  if (e - b < kParallelReduceThreshold) {
    BinSet bins(map.bins);
    bins.add(refs, b, e, ix);
    evaluate(bins);
  } else {
    ParallelBinning body(refs, ix, map.bins);
    tbb::parallel_reduce(tbb::blocked_range<uint32_t>(b, e, kGrain), body);
    evaluate(body.bins);
  }
  return out;
}

/// Partitions [b, e) stably into [b, m), the primitives whose bin on `axis` lies below `position` (m - b
/// of them, known from the bins), and [m, e), from refs into out, gathering each side's centroid bounds.
/// Branch-free: each reference is written at the cursor of its side (a conditional move, not a
/// mispredicted branch).
void BinnedBuilder::partition(const BinRef* refs, BinRef* out, uint32_t b, uint32_t m, uint32_t e, int axis,
                              int position, const BinMapping& map, Box4& left_c, Box4& right_c) {
  const float lo = map.lo[axis], scale = map.scale[axis];
  const __m128 inf = _mm_set1_ps(kInf), minus_inf = _mm_set1_ps(-kInf);
  uint32_t l = b, r = m;
  for (uint32_t k = b; k < e; ++k) {
    const BinRef& ref = refs[k];
    const float c_axis = (ref.lo[axis] + ref.hi[axis]) * 0.5f;  // lane `axis` of center(), bit for bit
    const bool left = std::clamp(int((c_axis - lo) * scale), 0, map.bins - 1) < position;
    out[left ? l : r] = ref;
    l += left;
    r += !left;
    const __m128 c = ref.center(), mask = _mm_castsi128_ps(_mm_set1_epi32(-int(left)));
    left_c.extend(_mm_blendv_ps(inf, c, mask), _mm_blendv_ps(minus_inf, c, mask));
    right_c.extend(_mm_blendv_ps(c, inf, mask), _mm_blendv_ps(c, minus_inf, mask));
  }
}

}  // namespace

BvhBuildResult build_bvh(const BvhSahConfig& config, std::span<const AABB> bounds, std::span<const vec3>) {
  return BinnedBuilder(config, bounds).run();
}

}  // namespace ab
