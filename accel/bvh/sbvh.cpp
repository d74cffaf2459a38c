// The spatial-split BVH builder (bvh-sbvh): Stich, Friedrich and Dietrich 2009, "Spatial splits in bounding
// volume hierarchies". At each node the best object split is found by the binned SAH of bvh-sah (Wald 2007,
// binned_split.h). When its two children overlap by more than alpha times the root's surface area, a spatial
// split is also priced: the node's box is cut into equal bins per axis, every reference is clipped into each
// bin it straddles (the primitive set's clipped bounds through clip_into_child, the k-d trees' conservative
// clipping with its positional margin), and the bin boundaries are swept with the references that start left
// of a boundary on its left and those that end right of it on its right. The cheaper split wins; a spatial
// split then keeps each straddling reference whole on one side when that is cheaper than splitting it (the
// paper's reference unsplitting) and clips the rest into both children.
//
// Why the hits stay identical: a split reference's boxes are the bounds of the primitive's parts on each
// side of the plane, so every point of a primitive lies in the box of at least one of its references and
// the conservative box test reaches it; each reference is tested with the one kernel on the original ray
// (a duplicate gives the same hit, and the acceptance rule keeps the best one).
//
// The reference budget: the buffer has room for max(N, ref_budget x N) references; each node owns a range
// of it (its references and some free room) and gives its children the free room in proportion to their
// reference counts, so a spatial split that does not fit its node's room is not taken. The tree is the same
// for any number of threads (every reduction is a min, a max or an integer sum; subtrees use disjoint ranges
// and slots).
#include "accel/bvh/sbvh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <memory>
#include <vector>

#include "accel/bvh/binned_split.h"
#include "accel/bvh/sah_split.h"
#include "accel/bvh/slots.h"
#include "accel/common/conservative_insertion.h"

namespace ab {

namespace {

/// The primitives as clip_into_child (conservative_insertion.h) sees them.
struct ClipSource {
  std::span<const AABB> all;
  const ClippedBoundsFn& clip;

  AABB bounds(uint32_t i) const { return all[i]; }
  AABB clipped_bounds(uint32_t i, const AABB& box) const { return clip(i, box); }
};

/// A node's part of the reference buffer: its references [b, e) and the free room [e, end) left by its
/// share of the reference budget.
struct RefRange {
  uint32_t b, e, end;
};

AABB box_of(const BinRef& r) {
  return {{r.lo[0], r.lo[1], r.lo[2]}, {r.hi[0], r.hi[1], r.hi[2]}};
}
BinRef ref_of(const AABB& box, uint32_t id) {
  return {{box.lo.x, box.lo.y, box.lo.z}, id, {box.hi.x, box.hi.y, box.hi.z}, 0.0f};
}
Box4 box4_of(const AABB& b) {
  return {_mm_setr_ps(b.lo.x, b.lo.y, b.lo.z, 0.0f), _mm_setr_ps(b.hi.x, b.hi.y, b.hi.z, 0.0f)};
}

/// What clipping a reference at a node needs: the primitives, the node's spatial bins and margin.
struct Clipper {
  ClipSource source;
  BinMapping map;  ///< equal bins over the node's box
  float margin;    ///< insertion_margin of the node's box

  /// The position of bin boundary k on axis a.
  float plane(int a, int k) const { return map.lo[a] + float(k) / map.scale[a]; }
  /// Ref's box cut to [lo, hi] on axis a.
  AABB slab(const BinRef& ref, int a, float lo, float hi) const {
    AABB child = box_of(ref);
    child.lo[a] = std::clamp(lo, child.lo[a], child.hi[a]);
    child.hi[a] = std::clamp(hi, child.lo[a], child.hi[a]);
    return child;
  }
  /// The bounds of the part of ref's primitive in ref's box cut to [lo, hi] on axis a.
  AABB piece(const BinRef& ref, int a, float lo, float hi) const {
    return clip_into_child(source, ref.id, slab(ref, a, lo, hi), margin);
  }
};

/// A reference straddling more bins than this is binned by its box cut to each bin instead of its
/// primitive's clipped part (only for pricing; a split reference is still clipped), which bounds the
/// clipping work per reference and node: large triangles spanning the whole node (the hostile generators)
/// would otherwise cost a clip per bin, axis and level.
constexpr int kMaxClippedBins = 4;

/// The spatial bins of one node on the three axes (axis a, bin k at a * nb + k): the box of the references'
/// parts inside each bin and how many references start (entry) and end (exit) in it. Reducible in parallel.
struct SpatialBins {
  int nb;
  std::array<Box4, 3 * kMaxBins> box;
  std::array<uint32_t, 3 * kMaxBins> entry, exit;

  explicit SpatialBins(int bins) : nb(bins) {
    for (int k = 0; k < 3 * nb; ++k) box[k] = Box4::empty(), entry[k] = exit[k] = 0;
  }
  void add(const BinRef* refs, uint32_t b, uint32_t e, const Clipper& cx) {
    for (uint32_t k = b; k < e; ++k)
      for (int a = 0; a < 3; ++a)
        if (cx.map.scale[a] > 0.0f) add(refs[k], a, cx);
  }
  void add(const BinRef& ref, int a, const Clipper& cx) {
    const int first = cx.map.bin(a, ref.lo[a]), last = cx.map.bin(a, ref.hi[a]);
    ++entry[a * nb + first];
    ++exit[a * nb + last];
    if (first == last) return box[a * nb + first].extend(ref.lo4(), ref.hi4());
    const bool clip = last - first < kMaxClippedBins;
    for (int k = first; k <= last; ++k) {
      const float lo = k == first ? ref.lo[a] : cx.plane(a, k);
      const float hi = k == last ? ref.hi[a] : cx.plane(a, k + 1);
      box[a * nb + k].extend(box4_of(clip ? cx.piece(ref, a, lo, hi) : cx.slab(ref, a, lo, hi)));
    }
  }
  void merge(const SpatialBins& o) {
    for (int k = 0; k < 3 * nb; ++k) box[k].extend(o.box[k]), entry[k] += o.entry[k], exit[k] += o.exit[k];
  }
};

/// TBB body binning a large node spatially (a SpatialBins is copied only when a subrange is stolen).
struct ParallelSpatialBinning {
  const BinRef* refs;
  const Clipper& cx;
  SpatialBins bins;

  ParallelSpatialBinning(const BinRef* r, const Clipper& c) : refs(r), cx(c), bins(c.map.bins) {}
  ParallelSpatialBinning(ParallelSpatialBinning& o, tbb::split) : refs(o.refs), cx(o.cx), bins(o.bins.nb) {}
  void operator()(const tbb::blocked_range<uint32_t>& r) { bins.add(refs, r.begin(), r.end(), cx); }
  void join(const ParallelSpatialBinning& o) { bins.merge(o.bins); }
};

/// The cheapest spatial split: axis, boundary (bins [0, position) left), cost, and the children's counts
/// (straddling references counted on both sides) and boxes (unions of bins).
struct SpatialSplit {
  SahSplit sah;
  uint32_t left_count = 0, right_count = 0;
  Box4 left = Box4::empty(), right = Box4::empty();
};

/// Sweeps every bin boundary of every axis of `bins` (suffix boxes and exit counts right to left, then
/// prefix boxes and entry counts left to right); the first cheapest boundary with both sides non-empty and
/// at most `room` references on the two sides wins.
SpatialSplit best_spatial_split(const SpatialBins& bins, const BinMapping& map, float parent_area,
                                const SahCosts& costs, uint32_t room) {
  const int n = bins.nb;
  SpatialSplit best;
  for (int a = 0; a < 3; ++a) {
    if (!(map.scale[a] > 0.0f)) continue;
    std::array<float, kMaxBins> right_area;
    std::array<uint32_t, kMaxBins> right_count;
    Box4 acc = Box4::empty();
    uint32_t count = 0;
    for (int i = n - 1; i > 0; --i) {
      acc.extend(bins.box[a * n + i]);
      count += bins.exit[a * n + i];
      right_area[i] = acc.area();
      right_count[i] = count;
    }
    acc = Box4::empty();
    count = 0;
    for (int i = 1; i < n; ++i) {
      acc.extend(bins.box[a * n + i - 1]);
      count += bins.entry[a * n + i - 1];
      if (count == 0 || right_count[i] == 0 || uint64_t(count) + right_count[i] > room) continue;
      const float c = costs.split(parent_area, acc.area(), count, right_area[i], right_count[i]);
      if (c < best.sah.cost) best = {{a, i, c}, count, right_count[i]};
    }
  }
  if (best.sah.axis < 0) return best;
  for (int k = 0; k < n; ++k)
    (k < best.sah.position ? best.left : best.right).extend(bins.box[best.sah.axis * n + k]);
  return best;
}

/// The split chosen at a node: the object split (always searched) and the spatial one when it is cheaper.
struct SplitChoice {
  BinMapping map;          ///< the object split's centroid bins
  BinMapping spatial_map;  ///< the spatial split's bins over the node's box
  float margin = 0.0f;     ///< insertion_margin of the node's box
  BinnedSplit object;
  SpatialSplit spatial;
  bool use_spatial = false;

  /// The SAH split that decides between a leaf and a split.
  const SahSplit& best() const { return use_spatial ? spatial.sah : object.sah; }
};

/// The builder (see the top of the file): one reference buffer with room for the budget, the slots of
/// build_bvh's layout (a range of room C takes at most 2C - 1 slots), and the recursion.
class SbvhBuilder {
 public:
  SbvhBuilder(const BvhSbvhConfig& config, std::span<const AABB> bounds, const ClippedBoundsFn& clip);

  /// Builds the tree and returns the flattened result (leaf order with the references' ids).
  BvhBuildResult run();

 private:
  void build(uint32_t p, RefRange r, int depth);
  SplitChoice choose_split(RefRange r, const NodeBounds& nb) const;
  SpatialSplit find_spatial_split(RefRange r, const Clipper& cx, float parent_area) const;
  void partition_object(RefRange r, const SplitChoice& c, std::vector<BinRef>& left,
                        std::vector<BinRef>& right) const;
  void partition_spatial(RefRange r, const SpatialSplit& s, const Clipper& cx, std::vector<BinRef>& left,
                         std::vector<BinRef>& right) const;
  std::array<RefRange, 2> place(RefRange r, const std::vector<BinRef>& left,
                                const std::vector<BinRef>& right);
  std::vector<uint32_t> compact_leaves();

  const BvhSbvhConfig& config_;
  ClipSource source_;
  size_t n_, room_;
  float root_area_ = 0.0f;
  std::unique_ptr<BinRef[]> refs_;  ///< uninitialized beyond the references written
  BvhSlots slots_;
};

SbvhBuilder::SbvhBuilder(const BvhSbvhConfig& config, std::span<const AABB> bounds,
                         const ClippedBoundsFn& clip)
    : config_(config),
      source_{bounds, clip},
      n_(bounds.size()),
      room_(std::max(n_, size_t(config.ref_budget * double(n_)))),
      refs_(std::make_unique_for_overwrite<BinRef[]>(room_)),
      slots_(room_) {
  for (size_t i = 0; i < n_; ++i) refs_[i] = ref_of(bounds[i], uint32_t(i));
}

BvhBuildResult SbvhBuilder::run() {
  if (n_ == 0) return flatten_bvh_slots(slots_, {});
  root_area_ = bounds_of_refs(refs_.get(), 0, n_).box.area();
  build(0, {0, uint32_t(n_), uint32_t(room_)}, 0);
  return flatten_bvh_slots(slots_, compact_leaves());
}

/// Builds the subtree of slot p over the references of r.
void SbvhBuilder::build(uint32_t p, RefRange r, int depth) {
  const NodeBounds nb = bounds_of_refs(refs_.get(), r.b, r.e);
  slots_.set_box(p, nb.box.aabb());
  const uint32_t n = r.e - r.b;
  if (depth >= config_.max_depth || n == 1) return slots_.set_leaf(p, r.b, r.e);
  const SplitChoice c = choose_split(r, nb);
  const uint32_t decision = sah_decision(n, c.best(), config_);
  if (decision == 0) return slots_.set_leaf(p, r.b, r.e);
  std::array<RefRange, 2> kids;
  {
    std::vector<BinRef> left, right;
    if (decision == n && c.use_spatial) {
      partition_spatial(r, c.spatial, Clipper{source_, c.spatial_map, c.margin}, left, right);
    } else if (decision == n) {
      partition_object(r, c, left, right);
    }
    if (left.empty() || right.empty()) {  // forced split in the middle of the current order
      left.assign(&refs_[r.b], &refs_[r.b + n / 2]);
      right.assign(&refs_[r.b + n / 2], &refs_[r.e]);
    }
    kids = place(r, left, right);
  }
  const uint32_t right_slot = slots_.set_interior(p, kids[0].b, kids[1].b);
  auto build_left = [&] { build(p + 1, kids[0], depth + 1); };
  auto build_right = [&] { build(right_slot, kids[1], depth + 1); };
  if (n >= config_.parallel_threshold) {
    tbb::parallel_invoke(build_left, build_right);
  } else {
    build_left();
    build_right();
  }
}

/// The object split, and the spatial split when the object split's children overlap by more than alpha
/// times the root's area (or no object split exists) and its references fit the node's room.
SplitChoice SbvhBuilder::choose_split(RefRange r, const NodeBounds& nb) const {
  const uint32_t n = r.e - r.b;
  const int bins = std::max(4, int(std::min(uint32_t(config_.bins), n)));
  const AABB box = nb.box.aabb();
  SplitChoice c{BinMapping(nb.centroids.aabb(), bins), BinMapping(AABB{}, 1), insertion_margin(box), {}, {}};
  c.object = find_binned_split(refs_.get(), r.b, r.e, nb.box, c.map, config_.costs);
  if (r.end == r.e) return c;  // no room for another reference
  if (c.object.sah.axis >= 0) {
    const float overlap = AABB::intersection(c.object.left.aabb(), c.object.right.aabb()).area();
    if (!(double(overlap) > config_.alpha * double(root_area_))) return c;
  }
  const int spatial_bins = std::max(4, int(std::min(uint32_t(config_.spatial_bins), n)));
  c.spatial_map = BinMapping(box, spatial_bins);
  c.spatial = find_spatial_split(r, Clipper{source_, c.spatial_map, c.margin}, nb.box.area());
  c.use_spatial = c.spatial.sah.axis >= 0 && c.spatial.sah.cost < c.object.sah.cost;
  return c;
}

/// Bins the node's references spatially (in parallel for large nodes) and sweeps the bins.
SpatialSplit SbvhBuilder::find_spatial_split(RefRange r, const Clipper& cx, float parent_area) const {
  if (r.e - r.b < kParallelReduceThreshold) {
    SpatialBins bins(cx.map.bins);
    bins.add(refs_.get(), r.b, r.e, cx);
    return best_spatial_split(bins, cx.map, parent_area, config_.costs, r.end - r.b);
  }
  ParallelSpatialBinning body(refs_.get(), cx);
  tbb::parallel_reduce(tbb::blocked_range<uint32_t>(r.b, r.e, kGrain), body);
  return best_spatial_split(body.bins, cx.map, parent_area, config_.costs, r.end - r.b);
}

/// Each reference to the side of its centroid's bin (the binned builder's rule, bit for bit).
void SbvhBuilder::partition_object(RefRange r, const SplitChoice& c, std::vector<BinRef>& left,
                                   std::vector<BinRef>& right) const {
  const int a = c.object.sah.axis;
  left.reserve(c.object.left_count);
  right.reserve(r.e - r.b - c.object.left_count);
  for (uint32_t k = r.b; k < r.e; ++k) {
    const BinRef& ref = refs_[k];
    (c.map.bin(a, (ref.lo[a] + ref.hi[a]) * 0.5f) < c.object.sah.position ? left : right).push_back(ref);
  }
}

/// References left or right of the plane go whole; a straddling one stays whole on one side when that
/// prices lower than splitting it (reference unsplitting, Stich et al. 2009, section 4.4: A_L N_L + A_R N_R
/// against (A_L u B) N_L + A_R (N_R - 1) and A_L (N_L - 1) + (A_R u B) N_R), else it is clipped into both.
void SbvhBuilder::partition_spatial(RefRange r, const SpatialSplit& s, const Clipper& cx,
                                    std::vector<BinRef>& left, std::vector<BinRef>& right) const {
  const int a = s.sah.axis;
  const float plane = cx.plane(a, s.sah.position);
  Box4 lbox = s.left, rbox = s.right;
  float nl = float(s.left_count), nr = float(s.right_count);
  for (uint32_t k = r.b; k < r.e; ++k) {
    const BinRef& ref = refs_[k];
    if (cx.map.bin(a, ref.hi[a]) < s.sah.position) {
      left.push_back(ref);
    } else if (cx.map.bin(a, ref.lo[a]) >= s.sah.position) {
      right.push_back(ref);
    } else {
      Box4 lb = lbox, rb = rbox;
      lb.extend(ref.lo4(), ref.hi4());
      rb.extend(ref.lo4(), ref.hi4());
      const float split = lbox.area() * nl + rbox.area() * nr;
      const float all_left = lb.area() * nl + rbox.area() * (nr - 1.0f);
      const float all_right = lbox.area() * (nl - 1.0f) + rb.area() * nr;
      if (all_left < split && all_left <= all_right && nr > 1.0f) {
        left.push_back(ref), lbox = lb, nr -= 1.0f;
      } else if (all_right < split && nl > 1.0f) {
        right.push_back(ref), rbox = rb, nl -= 1.0f;
      } else {
        left.push_back(ref_of(cx.piece(ref, a, ref.lo[a], plane), ref.id));
        right.push_back(ref_of(cx.piece(ref, a, plane, ref.hi[a]), ref.id));
      }
    }
  }
}

/// Writes the children's references into r: left at r.b, right after the left's room; the free room is
/// shared in proportion to the children's reference counts.
std::array<RefRange, 2> SbvhBuilder::place(RefRange r, const std::vector<BinRef>& left,
                                           const std::vector<BinRef>& right) {
  const uint64_t nl = left.size(), nr = right.size(), free = uint64_t(r.end - r.b) - nl - nr;
  const uint32_t left_room = uint32_t(nl + free * nl / (nl + nr));
  std::copy(left.begin(), left.end(), &refs_[r.b]);
  std::copy(right.begin(), right.end(), &refs_[r.b + left_room]);
  return {RefRange{r.b, uint32_t(r.b + nl), r.b + left_room},
          RefRange{r.b + left_room, uint32_t(r.b + left_room + nr), r.end}};
}

/// The leaves' references moved together in depth-first order (left child first, as flatten_bvh_slots
/// visits them): returns their ids and points every leaf at its new range.
std::vector<uint32_t> SbvhBuilder::compact_leaves() {
  std::vector<uint32_t> order;
  order.reserve(room_);
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const uint32_t p = stack.back();
    stack.pop_back();
    BvhNode& node = slots_.slots[p];
    if (!node.is_leaf()) {
      stack.push_back(node.offset);
      stack.push_back(p + 1);
      continue;
    }
    const uint32_t first = uint32_t(order.size());
    for (uint32_t k = node.offset; k < node.offset + node.count; ++k) order.push_back(refs_[k].id);
    node.offset = first;
  }
  return order;
}

}  // namespace

BvhBuildResult build_bvh(const BvhSbvhConfig& config, std::span<const AABB> bounds,
                         const ClippedBoundsFn& clipped_bounds) {
  return SbvhBuilder(config, bounds, clipped_bounds).run();
}

}  // namespace ab
