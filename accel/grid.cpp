#include "accel/grid.h"

#include "accel/clip.h"
#include "accel/registry.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>

namespace ab {

GridConfig read_grid_config(Params& params) {
  GridConfig c;
  c.lambda = params.get_float("lambda", c.lambda, 0.01, 100.0);
  c.max_cells = uint64_t(params.get_int("max_cells", (long long)c.max_cells, 1, 1ll << 31));
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
  const double budget = std::min(std::pow(config.lambda, 3.0) * double(std::max<size_t>(n, 1)), double(config.max_cells));
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

namespace {

constexpr size_t kBlock = 2048;  // primitives per insertion block (fixed: the result is thread-independent)

/// Margin covering the inflation of every cell box (inflate_for_insertion grows a box by 2^-18 of the
/// largest of its extent and coordinates), so the candidate range of a primitive misses no cell whose
/// inflated box it could touch.
float insertion_margin(const GridLayout& g) {
  const vec3 e = g.box.extent();
  float scale = std::max({e.x, e.y, e.z});
  for (int a = 0; a < 3; ++a) scale = std::max({scale, std::fabs(g.box.lo[a]), std::fabs(g.box.hi[a])});
  return scale * 0x1p-17f;
}

/// Appends (cell, id) for every cell primitive id goes into.
void insert_primitive(const GridLayout& g, uint32_t id, const AABB& b, float margin, const OverlapTest& overlaps,
                      std::vector<uint64_t>& out) {
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = g.cell_of(a, b.lo[a] - margin);
    hi[a] = g.cell_of(a, b.hi[a] + margin);
  }
  // A range that is one cell thick on two axes needs no test: the primitive is connected, so it meets every
  // slab its bounds span (a cell added only because of the margin is harmless, just one more reference).
  const bool line = (lo[0] != hi[0]) + (lo[1] != hi[1]) + (lo[2] != hi[2]) <= 1;
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x)
        if (line || overlaps(id, inflate_for_insertion(g.cell_box(x, y, z))))
          out.push_back((uint64_t(g.index(x, y, z)) << 32) | id);
}

}  // namespace

GridCells build_grid_cells(const GridLayout& g, std::span<const AABB> prim_bounds, const OverlapTest& overlaps) {
  GridCells cells;
  const size_t n = prim_bounds.size(), blocks = (n + kBlock - 1) / kBlock;
  cells.offsets.assign(g.cells() + 1, 0);
  std::vector<std::vector<uint64_t>> pairs(blocks);
  const float margin = insertion_margin(g);
  // Pass 1: the (cell, id) pairs of each block, and the per-cell counts.
  tbb::parallel_for(size_t(0), blocks, [&](size_t blk) {
    const size_t begin = blk * kBlock, end = std::min(n, begin + kBlock);
    for (size_t i = begin; i < end; ++i)
      if (!prim_bounds[i].empty()) insert_primitive(g, uint32_t(i), prim_bounds[i], margin, overlaps, pairs[blk]);
    for (uint64_t p : pairs[blk]) std::atomic_ref<uint32_t>(cells.offsets[(p >> 32) + 1]).fetch_add(1, std::memory_order_relaxed);
  });
  for (size_t c = 1; c < cells.offsets.size(); ++c) cells.offsets[c] += cells.offsets[c - 1];
  // Pass 2: fill in block order, so the ids of a cell come out ascending.
  cells.ids.resize(cells.offsets.back());
  std::vector<uint32_t> cursor(cells.offsets.begin(), cells.offsets.end() - 1);
  for (const auto& block : pairs)
    for (uint64_t p : block) cells.ids[cursor[p >> 32]++] = uint32_t(p);
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

BuildStats grid_stats(const GridLayout& g, const GridCells& cells, size_t primitives, const GridConfig& config) {
  BuildStats s;
  s.primitives = primitives;
  const size_t n = g.cells();
  s.nodes = n;
  s.leaves = n;
  s.references = cells.ids.size();
  std::vector<uint64_t> histogram;
  for (size_t c = 0; c < n; ++c) {
    const uint32_t size = cells.offsets[c + 1] - cells.offsets[c];
    if (size >= histogram.size()) histogram.resize(size + 1);
    ++histogram[size];
  }
  for (size_t k = 0; k < histogram.size(); ++k)
    if (histogram[k]) s.leaf_size_histogram[uint32_t(k)] = histogram[k];
  s.empty_leaves = histogram.empty() ? 0 : histogram[0];
  s.bytes = (cells.offsets.size() + cells.ids.size()) * sizeof(uint32_t);
  s.extra["resolution"] = {g.res[0], g.res[1], g.res[2]};
  s.extra["lambda"] = config.lambda;
  s.extra["cells"] = n;
  return s;
}

namespace {
const Registrar kRegisterGrid{structure_info<Grid>(
    "grid", "uniform grid, exact insertion, 3D-DDA (Amanatides and Woo 1987) with mailboxing", 20)};
}  // namespace

}  // namespace ab
