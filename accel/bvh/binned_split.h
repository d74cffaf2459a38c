// The binned SAH split search over references (Wald 2007, "On fast construction of SAH-based bounding volume
// hierarchies"), shared by the binned builder (binned.cpp) and the spatial-split builder's object splits
// (sbvh.cpp): the reference layout, vector boxes, the bins of a node on three axes and the sweep over them.
#pragma once

#include <immintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <array>
#include <cstddef>
#include <cstdint>

#include "accel/bvh/sah_split.h"
#include "accel/common/binning.h"
#include "accel/common/sah.h"
#include "accel/core/aabb.h"

namespace ab {
/// Nodes at least this large bin and bound their primitives with a parallel reduction. The reductions use
/// only min, max and integer sums, which are exact, so the result does not depend on how TBB splits.
inline constexpr size_t kParallelReduceThreshold = 1u << 15;
inline constexpr size_t kGrain = 1u << 12;
inline constexpr int kMaxBins = 256;

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
  /// 0 when empty (the extent is clamped at 0 instead of branching); with the extent multiplied by `frame`
  /// (a power of two, sah.h's area_frame), which leaves it exact.
  float area(float frame = 1.0f) const {
    const __m128 d = _mm_mul_ps(_mm_max_ps(_mm_sub_ps(hi, lo), _mm_setzero_ps()), _mm_set1_ps(frame));
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

/// A box as one 256-bit vector, lo in the low half and -hi in the high half, so that one minimum extends
/// both bounds (Wald 2007's bin update in half the instructions; the negation is exact, so the bounds are
/// the same bits as a Box4's). The empty box is +inf in every lane. Read and written with unaligned
/// loads and stores (float[8]), so that a misplaced BinSet could never fault; BinSet aligns its bins to 32
/// bytes, since a 32-byte access that splits a cache line is slow and defeats the store-to-load forwarding
/// the bin updates rely on (with the bins at offset 4, every other one did, and the build lost 5-10 %).
struct NegBox8 {
  float v[8];

  /// The empty box.
  static NegBox8 empty() {
    NegBox8 b;
    _mm256_storeu_ps(b.v, _mm256_set1_ps(kInf));
    return b;
  }
  /// The box of a reference: its lo (id lane zeroed) and its negated hi.
  static __m256 of(const BinRef& ref) {
    const __m256 keep = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, -1));
    const __m256 sign = _mm256_setr_ps(0.0f, 0.0f, 0.0f, 0.0f, -0.0f, -0.0f, -0.0f, -0.0f);
    return _mm256_xor_ps(_mm256_and_ps(_mm256_load_ps(ref.lo), keep), sign);
  }
  /// The centre of a box in this form: (lo - (-hi)) * 0.5, the same bits as BinRef::center() (subtracting
  /// a negated value is adding it, exactly).
  static __m128 center(__m256 x) {
    return _mm_mul_ps(_mm_sub_ps(_mm256_castps256_ps128(x), _mm256_extractf128_ps(x, 1)), _mm_set1_ps(0.5f));
  }
  __m256 get() const { return _mm256_loadu_ps(v); }
  void extend(__m256 b) { _mm256_storeu_ps(v, _mm256_min_ps(get(), b)); }
  void extend(const NegBox8& b) { extend(b.get()); }
  /// The same box as two vectors (lane 3: 0 and 0, or +inf and -inf when empty, as a Box4's).
  Box4 box4() const { return box4(get()); }
  /// The Box4 of a box in this form.
  static Box4 box4(__m256 x) {
    const __m128 hi = _mm_xor_ps(_mm256_extractf128_ps(x, 1), _mm_set1_ps(-0.0f));
    return {_mm256_castps256_ps128(x), hi};
  }
};

static_assert(sizeof(NegBox8) == 32);  // BinSet::put addresses the bins by byte offsets of 32 per bin

/// The bins of one node on the three axes, reducible in parallel: the box of axis a, bin k at a * nb + k,
/// its count at 4 k + a (the three axes' counts of a bin are one vector for the sweep).
struct BinSet {
  int nb;
  alignas(32) std::array<NegBox8, 3 * kMaxBins> box;  ///< 32-byte aligned: no access splits a cache line
  alignas(16) std::array<uint32_t, 4 * kMaxBins> count;

  explicit BinSet(int bins) : nb(bins) {
    for (int k = 0; k < 3 * nb; ++k) box[k] = NegBox8::empty();
    for (int k = 0; k < 4 * nb; ++k) count[k] = 0;
  }
  /// The counts of bin k on the three axes (lane 3: 0).
  __m128i counts(int k) const { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(&count[4 * k])); }
  /// Adds refs [b, e). A long range is binned into this set and a second one alternately and merged at
  /// the end: consecutive references often fall into the same bins, and with one set each would wait for
  /// the previous one's box update (a store-to-load chain). The sums and bounds are exact, so the bins are
  /// the same either way.
  void add(const BinRef* refs, uint32_t b, uint32_t e, const BinIndexer& ix) {
    uint32_t k = b;
    const __m128i first = axis_first();
    if (e - b < kTwoSetBinning) {
      for (; k < e; ++k) put(refs[k], ix, first);
      return;
    }
    BinSet odd(nb);
    for (; k + 1 < e; k += 2) {
      put(refs[k], ix, first);
      odd.put(refs[k + 1], ix, first);
    }
    if (k < e) put(refs[k], ix, first);
    merge(odd);
  }
  /// Adds the bins of o (exact: min, max and integer sums).
  void merge(const BinSet& o) {
    for (int k = 0; k < 3 * nb; ++k) box[k].extend(o.box[k]);
    for (int k = 0; k < 4 * nb; ++k) count[k] += o.count[k];
  }

 private:
  /// Ranges at least this long are binned into two sets.
  static constexpr uint32_t kTwoSetBinning = 256;

  /// The index of each axis's first bin (0, nb, 2 nb).
  __m128i axis_first() const { return _mm_setr_epi32(0, nb, 2 * nb, 0); }
  /// Adds the reference to its bin on each axis (axis_first() passed in). The byte offsets of its three boxes
  /// and counts are computed in one vector each.
  void put(const BinRef& ref, const BinIndexer& ix, __m128i axis_first) {
    const __m256 b = NegBox8::of(ref);
    const __m128i bin = ix.bins(NegBox8::center(b));
    alignas(16) int32_t box_at[4], count_at[4];
    const __m128i lane = _mm_setr_epi32(0, 1, 2, 3);
    _mm_store_si128(reinterpret_cast<__m128i*>(box_at), _mm_slli_epi32(_mm_add_epi32(bin, axis_first), 5));
    _mm_store_si128(reinterpret_cast<__m128i*>(count_at),
                    _mm_slli_epi32(_mm_add_epi32(_mm_slli_epi32(bin, 2), lane), 2));
    char* boxes = reinterpret_cast<char*>(box.data());
    char* counts = reinterpret_cast<char*>(count.data());
    for (int a = 0; a < 3; ++a) {
      reinterpret_cast<NegBox8*>(boxes + box_at[a])->extend(b);
      ++*reinterpret_cast<uint32_t*>(counts + count_at[a]);
    }
  }
};

/// The areas of three boxes at once, lane a of each half for box a, for two triples of boxes in the
/// (lo, -hi) form: the left ones in the low half of the result, the right ones in the high half. Each area
/// is bit for bit AABB::area() (its products, in its order): the extent hi - lo is computed as
/// -((-hi) + lo), which rounds to the same value (round to nearest is symmetric; a zero extent becomes -0,
/// which the clamp at 0 turns into +0 as before). The extents are multiplied by `frame` (area_frame of the
/// node, a power of two) before the products, so that areas at extreme scales neither overflow nor vanish.
inline __m256 areas3_pair(const __m256* left, const __m256* right, __m256 frame) {
  const __m256 sign = _mm256_set1_ps(-0.0f), zero = _mm256_setzero_ps();
  __m256 d[3];
  for (int a = 0; a < 3; ++a) {
    const __m256 lo = _mm256_permute2f128_ps(left[a], right[a], 0x20);
    const __m256 neg_hi = _mm256_permute2f128_ps(left[a], right[a], 0x31);
    d[a] = _mm256_mul_ps(_mm256_max_ps(_mm256_xor_ps(_mm256_add_ps(neg_hi, lo), sign), zero), frame);
  }
  // The transpose of _MM_TRANSPOSE4_PS (rows d[0], d[1], d[2], 0) in both halves at once; the fourth row
  // is not needed.
  const __m256 t0 = _mm256_unpacklo_ps(d[0], d[1]), t1 = _mm256_unpacklo_ps(d[2], zero);
  const __m256 t2 = _mm256_unpackhi_ps(d[0], d[1]), t3 = _mm256_unpackhi_ps(d[2], zero);
  const __m256 x = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 y = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 z = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s =
      _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, y), _mm256_mul_ps(y, z)), _mm256_mul_ps(z, x));
  return _mm256_mul_ps(_mm256_set1_ps(2.0f), s);
}

/// The cheapest bin boundary over the three axes, one axis per vector lane (Wald 2007): one pass
/// accumulates the prefix boxes from the left and the suffix boxes from the right together (their areas
/// computed two triples at a time), a second ranks the boundaries left to right. Within an axis a boundary
/// is ranked by left_area * left_count + right_area * right_count (the cost without its constant terms, so
/// no division per boundary); the first cheapest boundary of each axis is priced with SahCosts::split, and
/// the first cheapest axis wins. Axes whose lane in `axis_ok` is clear (flat centroid extent) are skipped.
/// Every area, the parent's included, is made in the node's area frame `frame` (sah.h).
inline SahSplit best_split_three_axes(const BinSet& bins, __m128 axis_ok, float parent_area,
                                      const SahCosts& costs, float frame) {
  const int n = bins.nb;
  auto extend = [&](__m256* acc, int k) {
    for (int a = 0; a < 3; ++a) acc[a] = _mm256_min_ps(acc[a], bins.box[a * n + k].get());
  };
  const __m256 empty = _mm256_set1_ps(kInf);
  // Boundary i (1 <= i < n) puts bins [0, i) left and [i, n) right; only [1, n) is written and read.
  __m128 left_area[kMaxBins], right_area[kMaxBins];
  __m128i left_count[kMaxBins], right_count[kMaxBins];
  __m256 left[3] = {empty, empty, empty}, right[3] = {empty, empty, empty};
  __m128i lc = _mm_setzero_si128(), rc = _mm_setzero_si128();
  const __m256 frame8 = _mm256_set1_ps(frame);
  for (int i = 1; i < n; ++i) {
    extend(left, i - 1);
    extend(right, n - i);
    lc = _mm_add_epi32(lc, bins.counts(i - 1));
    rc = _mm_add_epi32(rc, bins.counts(n - i));
    const __m256 areas = areas3_pair(left, right, frame8);
    left_area[i] = _mm256_castps256_ps128(areas);
    right_area[n - i] = _mm256_extractf128_ps(areas, 1);
    left_count[i] = lc;
    right_count[n - i] = rc;
  }
  __m128 best_w = _mm_set1_ps(kInf), best_la = _mm_setzero_ps(), best_ra = _mm_setzero_ps();
  __m128i best_i = _mm_setzero_si128(), best_lc = _mm_setzero_si128();
  for (int i = 1; i < n; ++i) {
    const __m128 la = left_area[i], ra = right_area[i];
    const __m128i cnt = left_count[i];
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
  alignas(16) int32_t bi[4], lcs[4], total[4];
  alignas(16) float bla[4], bra[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(bi), best_i);
  _mm_store_si128(reinterpret_cast<__m128i*>(lcs), best_lc);
  _mm_store_si128(reinterpret_cast<__m128i*>(total), _mm_add_epi32(lc, bins.counts(n - 1)));
  _mm_store_ps(bla, best_la);
  _mm_store_ps(bra, best_ra);
  SahSplit best;
  for (int a = 0; a < 3; ++a) {
    if (bi[a] == 0) continue;
    const float c = costs.split(parent_area, bla[a], uint32_t(lcs[a]), bra[a], uint32_t(total[a] - lcs[a]));
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

/// The box and the centroid box of refs [b, e): a parallel reduction for large ranges (min and max are
/// exact, so the result does not depend on how TBB splits).
inline NodeBounds bounds_of_refs(const BinRef* refs, size_t b, size_t e) {
  auto body = [&](const tbb::blocked_range<size_t>& r, NodeBounds acc) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      acc.box.extend(refs[k].lo4(), refs[k].hi4());
      const __m128 c = refs[k].center();
      acc.centroids.extend(c, c);
    }
    return acc;
  };
  if (e - b < kParallelReduceThreshold) return body(tbb::blocked_range<size_t>(b, e), NodeBounds{});
  return tbb::parallel_reduce(tbb::blocked_range<size_t>(b, e, kGrain), NodeBounds{}, body,
                              [](NodeBounds x, const NodeBounds& y) {
                                x.box.extend(y.box);
                                x.centroids.extend(y.centroids);
                                return x;
                              });
}

/// The cheapest bin boundary of refs [b, e) over the three axes (binned with `map`, over the node's box
/// `node_box`), with the children's boxes as unions of bins; large ranges bin in parallel (exact reductions,
/// so the result does not depend on the thread count).
inline BinnedSplit find_binned_split(const BinRef* refs, uint32_t b, uint32_t e, const Box4& node_box,
                                     const BinMapping& map, const SahCosts& costs) {
  const BinIndexer ix(map);
  BinnedSplit out;
  auto evaluate = [&](const BinSet& bins) {
    const __m128 axis_ok =
        _mm_cmpgt_ps(_mm_setr_ps(map.scale[0], map.scale[1], map.scale[2], 0.0f), _mm_setzero_ps());
    const float frame = area_frame(node_box.aabb().extent());
    out.sah = best_split_three_axes(bins, axis_ok, node_box.area(frame), costs, frame);
    if (out.sah.axis < 0) return;
    const int base = out.sah.axis * bins.nb;
    for (int k = 0; k < bins.nb; ++k) {
      (k < out.sah.position ? out.left : out.right).extend(bins.box[base + k].box4());
      if (k < out.sah.position) out.left_count += bins.count[4 * k + out.sah.axis];
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

}  // namespace ab
