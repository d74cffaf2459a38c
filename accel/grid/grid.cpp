#include "accel/grid/grid.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <utility>

#include "accel/common/conservative_insertion.h"
#include "accel/common/tree_stats.h"
#include "accel/core/clip.h"
#include "accel/core/registry.h"

namespace ab {

GridConfig GridConfig::read(Params& params) {
  GridConfig c;
  params.read("lambda", c.lambda, 0.01, 100.0);
  params.read("max_cells", c.max_cells, 1, double(1ll << 31));
  params.read("ref_budget", c.ref_budget, 1.0, 1e6);
  params.read("leaf_copies", c.leaf_copies, kLeafCopiesWords);
  return c;
}

// Resolution after Cleary and Wyvill 1988 / Woo 1990: cells proportional to the extent of each axis, the
// total a fixed multiple of the primitive count. Axes that would get fewer than one cell are given one
// and the budget is shared among the others (flat geometry gets a 2D or 1D grid, not a stretched 3D one).
GridLayout make_grid_layout(const AABB& bounds, size_t n, const GridConfig& config) {
  GridLayout g;
  g.res = {1, 1, 1};
  if (bounds.empty()) return g;
  g.box = bounds;
  const vec3 e = bounds.extent();
  const double budget =
      std::min(std::pow(config.lambda, 3.0) * double(std::max<size_t>(n, 1)), double(config.max_cells));
  bool active[3] = {e.x > 0.0f, e.y > 0.0f, e.z > 0.0f};
  double res[3] = {1.0, 1.0, 1.0};
  for (int round = 0; round < 3; ++round) {
    int d = 0;
    double volume = 1.0;
    for (int a = 0; a < 3; ++a)
      if (active[a]) ++d, volume *= double(e[a]);
    if (d == 0) break;
    const double k = std::pow(budget / volume, 1.0 / d);  // cells per unit length
    bool changed = false;
    for (int a = 0; a < 3; ++a) {
      if (!active[a]) continue;
      res[a] = double(e[a]) * k;
      if (res[a] < 1.0) res[a] = 1.0, active[a] = false, changed = true;
    }
    if (!changed) break;
  }
  for (int a = 0; a < 3; ++a) g.res[a] = int(std::clamp(std::round(res[a]), 1.0, double(1 << 20)));
  while (g.cells() > config.max_cells) {  // rounding may leave the product just above the cap
    const int a = int(std::max_element(g.res.begin(), g.res.end()) - g.res.begin());
    g.res[a] = std::max(1, g.res[a] - std::max(1, g.res[a] / 64));
  }
  for (int a = 0; a < 3; ++a) {
    g.cell_size[a] = e[a] / float(g.res[a]);
    g.inv_cell_size[a] = e[a] > 0.0f ? float(g.res[a]) / e[a] : 0.0f;
  }
  return g;
}

float insertion_margin(const GridLayout& g) {
  return 2.0f * InsertionMargin(g.box).of(g.box);
}

namespace {

constexpr size_t kBlock = 2048;  // primitives per insertion block (fixed: the result is thread-independent)

/// Cell range [lo, hi] per axis of a box widened by margin.
struct CellRange {
  int lo[3], hi[3];

  CellRange(const GridLayout& g, const AABB& b, float margin) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = g.cell_of(a, b.lo[a] - margin);
      hi[a] = g.cell_of(a, b.hi[a] + margin);
    }
  }
  /// True when the range is more than one cell thick on at most one axis.
  bool is_line() const { return (lo[0] != hi[0]) + (lo[1] != hi[1]) + (lo[2] != hi[2]) <= 1; }
};

/// Appends every cell of range r (z, then y, then x ascending).
void append_range(const GridLayout& g, const CellRange& r, uint32_t id, std::vector<uint64_t>& out) {
  for (int z = r.lo[2]; z <= r.hi[2]; ++z)
    for (int y = r.lo[1]; y <= r.hi[1]; ++y)
      for (int x = r.lo[0]; x <= r.hi[0]; ++x) out.push_back((uint64_t(g.index(x, y, z)) << 32) | id);
}

/// A convex polygon: a triangle clipped by four axis planes has at most 7 vertices; the capacity leaves
/// room for the extra crossings rounding can give a degenerate (zero-area) one, which never hits anyway.
struct SlabPolygon {
  static constexpr int kCapacity = 16;
  vec3 v[kCapacity];
  int n = 0;
};

/// Range of polygon p's coordinates on an axis.
void polygon_extent(const SlabPolygon& p, int axis, float& lo, float& hi) {
  lo = kInf, hi = -kInf;
  for (int i = 0; i < p.n; ++i) lo = std::min(lo, p.v[i][axis]), hi = std::max(hi, p.v[i][axis]);
}

/// Keeps the part of `in` with lo <= p[axis] <= hi (Sutherland and Hodgman 1974, against the planes that
/// actually cut it).
void clip_to_slab(const SlabPolygon& in, int axis, float lo, float hi, SlabPolygon& out) {
  SlabPolygon tmp;
  auto clip = [axis](const SlabPolygon& src, float plane, float sign, SlabPolygon& dst) {
    dst.n = 0;
    for (int i = 0; i < src.n; ++i) {
      const vec3& a = src.v[i];
      const vec3& b = src.v[i + 1 == src.n ? 0 : i + 1];
      const float da = sign * (a[axis] - plane), db = sign * (b[axis] - plane);
      if (da <= 0.0f && dst.n < SlabPolygon::kCapacity) dst.v[dst.n++] = a;
      if (((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) && dst.n < SlabPolygon::kCapacity)
        dst.v[dst.n++] = a + (da / (da - db)) * (b - a);
    }
  };
  float min_c, max_c;
  polygon_extent(in, axis, min_c, max_c);
  if (min_c > hi || max_c < lo) {
    out.n = 0;
  } else if (max_c <= hi) {  // only the lower plane cuts, if any
    if (min_c >= lo)
      out = in;
    else
      clip(in, lo, -1.0f, out);
  } else if (min_c >= lo) {  // only the upper plane cuts
    clip(in, hi, 1.0f, out);
  } else {
    clip(in, hi, 1.0f, tmp);
    clip(tmp, lo, -1.0f, out);
  }
}

/// The x extent of the part of polygon p with lo <= y <= hi: the same points clipping to that row would
/// give (the vertices inside it and the edges' crossings of its two planes), without building the polygon.
/// Empty (lo_x > hi_x) when the polygon misses the row.
void row_x_extent(const SlabPolygon& p, float lo, float hi, float& lo_x, float& hi_x) {
  lo_x = kInf, hi_x = -kInf;
  auto add = [&](float x) { lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x); };
  for (int i = 0; i < p.n; ++i) {
    const vec3& a = p.v[i];
    const vec3& b = p.v[i + 1 == p.n ? 0 : i + 1];
    if (a.y >= lo && a.y <= hi) add(a.x);
    for (const float plane : {lo, hi}) {
      const float da = a.y - plane, db = b.y - plane;
      if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) add(a.x + (da / (da - db)) * (b.x - a.x));
    }
  }
}

// Triangle voxelization by slab and row clipping (the scan conversion of Akenine-Moller and Aila's
// conservative voxelization, done with Sutherland-Hodgman clipping): for each z slab of the triangle's
// cell range, clip the triangle to the slab widened by the margin; for each row of the slab polygon's y
// range, the x extent of the slab polygon's part in the widened row (its clipped vertices, without building
// the polygon), widened again, gives the cells. The widened
// slabs and rows contain every cell box grown by InsertionMargin::inflate (whose growth is at most half the
// margin), so every cell the exact test against such a box accepts is found.
void voxelize_triangle(const GridLayout& g, const Triangle& t, uint32_t id, float margin,
                       std::vector<uint64_t>& out) {
  const CellRange r(g, t.bounds(), margin);
  if (r.is_line()) return append_range(g, r, id, out);  // connected: it meets every cell of a line
  SlabPolygon tri;
  tri.v[0] = t.v0, tri.v[1] = t.v1, tri.v[2] = t.v2, tri.n = 3;
  SlabPolygon slab;
  for (int z = r.lo[2]; z <= r.hi[2]; ++z) {
    if (r.lo[2] == r.hi[2])
      slab = tri;
    else
      clip_to_slab(tri, 2, g.plane(2, z) - margin, g.plane(2, z + 1) + margin, slab);
    if (slab.n == 0) continue;
    float lo, hi;
    polygon_extent(slab, 1, lo, hi);
    const int y0 = std::max(r.lo[1], g.cell_of(1, lo - margin)),
              y1 = std::min(r.hi[1], g.cell_of(1, hi + margin));
    for (int y = y0; y <= y1; ++y) {
      if (y0 == y1)
        polygon_extent(slab, 0, lo, hi);
      else
        row_x_extent(slab, g.plane(1, y) - margin, g.plane(1, y + 1) + margin, lo, hi);
      if (!(lo <= hi)) continue;
      const int x0 = std::max(r.lo[0], g.cell_of(0, lo - margin)),
                x1 = std::min(r.hi[0], g.cell_of(0, hi + margin));
      for (int x = x0; x <= x1; ++x) out.push_back((uint64_t(g.index(x, y, z)) << 32) | id);
    }
  }
}

}  // namespace

CellInserter box_test_inserter(const GridLayout& g, std::span<const AABB> prim_bounds, OverlapTest overlaps) {
  const float margin = insertion_margin(g);
  const InsertionMargin cells(g.box);
  return [&g, prim_bounds, overlaps = std::move(overlaps), margin, cells](uint32_t id,
                                                                          std::vector<uint64_t>& out) {
    if (prim_bounds[id].empty()) return;
    const CellRange r(g, prim_bounds[id], margin);
    // A range one cell thick on two axes needs no test: the primitive is connected, so it meets every
    // slab its bounds span (a cell added only because of the margin is harmless, one more reference).
    if (r.is_line()) return append_range(g, r, id, out);
    for (int z = r.lo[2]; z <= r.hi[2]; ++z)
      for (int y = r.lo[1]; y <= r.hi[1]; ++y)
        for (int x = r.lo[0]; x <= r.hi[0]; ++x)
          if (overlaps(id, cells.inflate(g.cell_box(x, y, z))))
            out.push_back((uint64_t(g.index(x, y, z)) << 32) | id);
  };
}

CellInserter triangle_inserter(const GridLayout& g, std::span<const Triangle> triangles) {
  const float margin = insertion_margin(g);
  return [&g, triangles, margin](uint32_t id, std::vector<uint64_t>& out) {
    voxelize_triangle(g, triangles[id], id, margin, out);
  };
}

namespace {

constexpr size_t kMaxBuckets = 256;  // cell ranges filled independently (fixed: thread-independent result)

/// The (cell, id) pairs of all primitives regrouped by bucket (a contiguous range of 2^shift cells), each
/// bucket's pairs in primitive order: a stable two-level counting sort whose scatter is parallel over blocks.
struct BucketedPairs {
  int shift = 0;
  size_t buckets = 1;
  std::vector<uint64_t> begin;  ///< bucket b's pairs are pairs[begin[b], begin[b + 1])
  std::unique_ptr<uint64_t[]> pairs;

  BucketedPairs(size_t cells, const std::vector<std::vector<uint64_t>>& blocks) {
    while (((cells - 1) >> shift) >= kMaxBuckets) ++shift;
    buckets = ((cells - 1) >> shift) + 1;
    const size_t nb = blocks.size();
    std::vector<uint64_t> start(nb * buckets, 0);  // per block and bucket: count, then write position
    tbb::parallel_for(size_t(0), nb, [&](size_t blk) {
      for (uint64_t p : blocks[blk]) ++start[blk * buckets + ((p >> 32) >> shift)];
    });
    begin.assign(buckets + 1, 0);
    uint64_t running = 0;
    for (size_t b = 0; b < buckets; ++b) {
      begin[b] = running;
      for (size_t blk = 0; blk < nb; ++blk) {  // count -> write position
        std::swap(start[blk * buckets + b], running);
        running += start[blk * buckets + b];
      }
    }
    begin[buckets] = running;
    pairs = std::make_unique_for_overwrite<uint64_t[]>(running);
    tbb::parallel_for(size_t(0), nb, [&](size_t blk) {
      uint64_t* cursor = &start[blk * buckets];
      for (uint64_t p : blocks[blk]) pairs[cursor[(p >> 32) >> shift]++] = p;
    });
  }
};

}  // namespace

GridCells build_grid_cells(const GridLayout& g, size_t n, const CellInserter& insert, uint64_t max_refs) {
  GridCells cells;
  const size_t blocks = (n + kBlock - 1) / kBlock, cell_count = g.cells();
  std::vector<std::vector<uint64_t>> block_pairs(blocks);
  // Pass 1: the (cell, id) pairs of each block of primitives, counted against max_refs every 64 of them.
  std::atomic<uint64_t> refs{0};
  tbb::parallel_for(size_t(0), blocks, [&](size_t blk) {
    const size_t begin = blk * kBlock, end = std::min(n, begin + kBlock);
    std::vector<uint64_t>& pairs = block_pairs[blk];
    pairs.reserve(4 * (end - begin));  // typical references per primitive: fewer regrowths
    size_t counted = 0;
    for (size_t i = begin; i < end && refs.load(std::memory_order_relaxed) <= max_refs; ++i) {
      insert(uint32_t(i), pairs);
      if ((i - begin) % 64 == 63 || i + 1 == end) refs += pairs.size() - std::exchange(counted, pairs.size());
    }
  });
  if (refs.load() > max_refs) {
    cells.over_budget = true;
    return cells;
  }
  // Pass 2: regroup by bucket of cells, keeping primitive order.
  const BucketedPairs bucketed(cell_count, block_pairs);
  std::vector<std::vector<uint64_t>>().swap(block_pairs);
  // Pass 3: each bucket counts, offsets and fills its own cells (primitive order: ids ascending per cell).
  cells.offsets.resize(cell_count + 1);
  cells.ids.resize(bucketed.begin.back());
  cells.offsets[cell_count] = uint32_t(bucketed.begin.back());
  tbb::parallel_for(size_t(0), bucketed.buckets, [&](size_t b) {
    const size_t c0 = b << bucketed.shift, c1 = std::min(cell_count, (b + 1) << bucketed.shift);
    const uint64_t* first = bucketed.pairs.get() + bucketed.begin[b];
    const uint64_t* last = bucketed.pairs.get() + bucketed.begin[b + 1];
    std::vector<uint32_t> cursor(c1 - c0, 0);
    for (const uint64_t* p = first; p != last; ++p) ++cursor[(*p >> 32) - c0];
    uint32_t running = uint32_t(bucketed.begin[b]);
    for (size_t c = c0; c < c1; ++c) {  // offsets, and the cursor of each cell at its first slot
      cells.offsets[c] = running;
      std::swap(cursor[c - c0], running);
      running += cursor[c - c0];
    }
    for (const uint64_t* p = first; p != last; ++p) cells.ids[cursor[(*p >> 32) - c0]++] = uint32_t(*p);
  });
  return cells;
}

GridWalk::GridWalk(const GridLayout& g, const Ray& ray, const RayBoxData& rd, float t0) {
  for (int a = 0; a < 3; ++a) {
    const float d = ray.dir[a];
    const bool moves = d != 0.0f && std::isfinite(rd.inv_dir[a]);
    step[a] = moves ? (d > 0.0f ? 1 : -1) : 0;
    int c = g.cell_of(a, ray.org[a] + ray.dir[a] * t0);
    if (step[a] == 0) {
      cell[a] = c;
      t_next[a] = kInf;
      continue;
    }
    // Never start ahead of the ray: the entry plane of the start cell must be crossed at or before t0.
    auto t_plane = [&](int i) { return (g.plane(a, i) - rd.org[a]) * rd.inv_dir[a]; };
    if (step[a] > 0) {
      while (c > 0 && t_plane(c) > t0) --c;
    } else {
      while (c < g.res[a] - 1 && t_plane(c + 1) > t0) ++c;
    }
    cell[a] = c;
    t_next[a] = t_plane(c + (step[a] > 0));
  }
}

namespace {

/// The grid as the one statistics walk sees it: the grid box is the root and every cell one of its leaves.
/// No node has an area for the walk (box() is empty): the tree SAH prices the visits of a tree, not the
/// steps of a 3D-DDA, so a grid reports no SAH cost.
struct GridStatsVisitor {
  /// The grid box (kGridBox) or a cell index.
  using Node = uint32_t;
  static constexpr Node kGridBox = 0xFFFFFFFFu;  ///< the root
  const GridCells& cells;                        ///< the cells
  uint32_t cell_count;                           ///< number of cells

  /// The grid box.
  Node root() const { return kGridBox; }
  /// No area (see above).
  AABB box(Node) const { return AABB{}; }
  /// True for the cells.
  bool is_leaf(Node n) const { return n != kGridBox; }
  /// Primitives of a cell.
  uint32_t count(Node n) const { return cells.offsets[n + 1] - cells.offsets[n]; }
  /// Every cell of the grid box.
  template <class F>
  void children(Node, F&& f) const {
    for (uint32_t c = 0; c < cell_count; ++c) f(c);
  }
};

}  // namespace

void gather_grid_stats(const GridLayout& g, const GridCells& cells, const GridConfig& config,
                       BuildStats& stats) {
  const size_t n = g.cells();
  if (cells.offsets.size() == n + 1) walk_tree_stats(GridStatsVisitor{cells, uint32_t(n)}, stats);
  // The grid box is the walk's root but not a node of the grid: a grid reports its cells as its nodes and
  // leaves, all at depth 0 (as it always has).
  stats.nodes = n;
  stats.max_depth = 0;
  stats.mean_leaf_depth = 0.0;
  stats.bytes = cells.offsets.size() * sizeof(uint32_t);  // the Grid adds its cells' references (LeafRefs)
  stats.extra["resolution"] = {g.res[0], g.res[1], g.res[2]};
  stats.extra["lambda"] = config.lambda;
  stats.extra["cells"] = n;
}

namespace {
const Registrar kRegisterGrid{structure_info<Grid>(
    "grid", "uniform grid, exact insertion, 3D-DDA (Amanatides and Woo 1987) with mailboxing", 20)};
}  // namespace

}  // namespace ab
