// Uniform grid over any primitive set: cells in compressed rows (offsets + ids), primitives inserted by
// exact primitive/box overlap against conservatively inflated cells, traversal by 3D-DDA
// (Amanatides and Woo 1987, "A fast voxel traversal algorithm for ray tracing") with a per-ray mailbox.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "accel/common/finite_primitives.h"
#include "accel/common/leaf_refs.h"
#include "accel/common/mailbox.h"
#include "accel/core/accelerator.h"
#include "accel/core/box_test.h"
#include "accel/core/params.h"
#include "accel/core/primitives.h"

namespace ab {

/// Configuration of the grid.
struct GridConfig {
  double lambda = 1.0;  ///< density: about lambda * cbrt(N) cells per axis for a cube (lambda^3 N cells)
  uint64_t max_cells = 1ull << 24;  ///< cap on the number of cells
  /// The cells hold at most this many references per primitive: a grid that would hold more is built
  /// again with lambda halved (an eighth of the cells) until it fits.
  double ref_budget = 32.0;
  LeafCopies leaf_copies = LeafCopies::kAuto;  ///< copy triangles into cell order (LeafRefs)

  /// Reads every field from params.
  static GridConfig read(Params& params);
};

/// The geometry of a grid: its box, resolution and cell size. Cell (x, y, z) spans planes x..x+1 etc.
struct GridLayout {
  AABB box;                         ///< the grid box
  std::array<int, 3> res{0, 0, 0};  ///< cells per axis
  vec3 cell_size{0.0f};             ///< extent of a cell per axis
  vec3 inv_cell_size{0.0f};         ///< 0 on a flat axis (which always has one cell)

  /// Number of cells.
  size_t cells() const { return size_t(res[0]) * size_t(res[1]) * size_t(res[2]); }
  /// Position of plane i (0..res) on axis a; plane res is exactly the box's upper face.
  float plane(int a, int i) const { return i >= res[a] ? box.hi[a] : box.lo[a] + float(i) * cell_size[a]; }
  /// Cell coordinate of position p on axis a, clamped to [0, res-1] (NaN gives 0).
  int cell_of(int a, float p) const {
    const float x = (p - box.lo[a]) * inv_cell_size[a];
    if (!(x >= 0.0f)) return 0;
    return x >= float(res[a] - 1) ? res[a] - 1 : int(x);
  }
  /// Linear index of cell (x, y, z).
  size_t index(int x, int y, int z) const {
    return (size_t(z) * size_t(res[1]) + size_t(y)) * size_t(res[0]) + size_t(x);
  }
  /// Box of cell (x, y, z).
  AABB cell_box(int x, int y, int z) const {
    return {{plane(0, x), plane(1, y), plane(2, z)}, {plane(0, x + 1), plane(1, y + 1), plane(2, z + 1)}};
  }
};

/// Resolution for n primitives in bounds: cells per axis proportional to the extent, about
/// lambda^3 * n cells overall, axes that would get less than one cell (flat ones) get one and the rest
/// share the budget; capped at max_cells.
GridLayout make_grid_layout(const AABB& bounds, size_t n, const GridConfig& config);

/// Cells in compressed rows: the ids of cell c are ids[offsets[c] .. offsets[c+1]), ascending.
struct GridCells {
  std::vector<uint32_t> offsets;  ///< cells + 1 row starts
  std::vector<uint32_t> ids;      ///< the cells' primitive ids, cell after cell
  bool over_budget = false;       ///< the references passed build_grid_cells' max_refs (nothing built)
};

/// Appends to `out` the cells primitive `id` goes into, each as (cell index << 32) | id, in ascending
/// cell order.
using CellInserter = std::function<void(uint32_t id, std::vector<uint64_t>& out)>;

/// Exact overlap of primitive i with a box (the primitive set's overlaps()).
using OverlapTest = std::function<bool(uint32_t, const AABB&)>;

/// Generic insertion (any primitive set): every cell of the primitive's margin-widened bounds whose
/// inflated box (InsertionMargin::inflate of the grid box) the primitive overlaps according to `overlaps`.
CellInserter box_test_inserter(const GridLayout& layout, std::span<const AABB> prim_bounds,
                               OverlapTest overlaps);

/// Triangle insertion by voxelization: the triangle is clipped to each slab of cells along z, the slab
/// polygon to each row along y, and the row polygon's x extent gives the cells. Every slab, row and extent
/// is widened by insertion_margin(), which covers every cell's inflation, so no cell the
/// generic test would accept is lost.
CellInserter triangle_inserter(const GridLayout& layout, std::span<const Triangle> triangles);

/// Margin covering the inflation of every cell box of the grid (InsertionMargin of the grid box, which no
/// cell's exceeds; this is twice the grid box's).
float insertion_margin(const GridLayout& layout);

/// Two-pass insertion of primitives [0, n) (collect the (cell, id) pairs per block of primitives on TBB,
/// then count and fill): deterministic for any thread count, the ids of every cell ascending. When the
/// references would pass max_refs, it stops early and returns no cells with over_budget set (the count
/// only grows, so that depends on the grid alone, not on the threads).
GridCells build_grid_cells(const GridLayout& layout, size_t n, const CellInserter& insert,
                           uint64_t max_refs = UINT64_MAX);

/// The state of a 3D-DDA walk: the current cell and, per axis, the step and the ray parameter of the
/// next plane crossing (computed directly from the plane position each time, never accumulated).
struct GridWalk {
  int cell[3];      ///< current cell coordinates
  int step[3];      ///< +1, -1 or 0 per axis
  float t_next[3];  ///< parameter of the next plane crossing per axis

  /// Starts the walk at parameter t0 (the ray's entry into the grid box).
  GridWalk(const GridLayout& g, const Ray& ray, const RayBoxData& rd, float t0);
  /// Parameter where the ray leaves the current cell.
  float exit() const { return std::min(t_next[0], std::min(t_next[1], t_next[2])); }
  /// Moves to the next cell; false when the ray leaves the grid.
  bool advance(const GridLayout& g, const RayBoxData& rd) {
    const int a =
        t_next[0] <= t_next[1] ? (t_next[0] <= t_next[2] ? 0 : 2) : (t_next[1] <= t_next[2] ? 1 : 2);
    if (step[a] == 0) return false;
    cell[a] += step[a];
    if (cell[a] < 0 || cell[a] >= g.res[a]) return false;
    t_next[a] = (g.plane(a, cell[a] + (step[a] > 0)) - rd.org[a]) * rd.inv_dir[a];
    return true;
  }
};

/// Statistics of a built grid for the one statistics walk (tree_stats.h: the cells as the leaves of the
/// grid box), with the resolution and the bytes of the cells' offsets (the caller adds its references').
void gather_grid_stats(const GridLayout& layout, const GridCells& cells, const GridConfig& config,
                       BuildStats& stats);

/// A uniform grid over primitive set P.
template <class P>
class Grid final : public AcceleratorBase<Grid<P>> {
 public:
  /// The primitive set.
  using Prims = P;
  /// The grid's configuration.
  using Config = GridConfig;

  /// Over prims with config; the build is separate (build()).
  Grid(std::shared_ptr<const P> prims, const Config& config) : prims_(std::move(prims)), config_(config) {}

  /// Bounds of the primitives.
  AABB bounds() const override { return prims_->bounds(); }
  /// The grid's geometry (for tests).
  const GridLayout& layout() const { return layout_; }
  /// The cells' offsets (for tests; their ids moved to ids()).
  const GridCells& cells() const { return cells_; }
  /// The cells' primitive ids, cell after cell (for tests).
  const std::vector<uint32_t>& ids() const { return leaves_.ids(); }

  /// Closest hit: walks the cells in ray order and stops once the best hit lies before the current
  /// cell's exit (best.t < the exit distance widened towards the origin), so a primitive in a later cell,
  /// which lies beyond that plane by more than the insertion margin, can neither beat nor tie it. A cell's
  /// primitives are its references in LeafRefs, tested as the trees' leaves are (once per ray: the mailbox).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters& c) const {
    if (leaves_.ids().empty()) return;
    if (far_origin(ray)) {
      for (size_t i = 0; i < prims_->size(); ++i) prims_->template intersect<kCount>(i, ray, best, inst, c);
      return;
    }
    const RayBoxData rd(ray);
    float t0 = ray.tmin, t1 = std::min(ray.tmax, best.t);
    if (!slab_test(layout_.box, rd, t0, t1)) return;
    GridWalk walk(layout_, ray, rd, t0);
    Mailbox mailbox;
    for (;;) {
      const auto [first, count] = enter_cell<kCount>(walk, c);
      leaves_.template intersect_unseen<kCount>(*prims_, first, count, ray, best, inst, c, mailbox);
      const float t_exit = widen_near(walk.exit());
      if (best.t < t_exit || t_exit > t1 || !walk.advance(layout_, rd)) return;
    }
  }

  /// Any hit within [tmin, tmax]: the same walk, stopping at the first primitive that reports one.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters& c) const {
    if (leaves_.ids().empty()) return false;
    if (far_origin(ray)) {
      for (size_t i = 0; i < prims_->size(); ++i)
        if (prims_->template occluded<kCount>(i, ray, c)) return true;
      return false;
    }
    const RayBoxData rd(ray);
    float t0 = ray.tmin, t1 = ray.tmax;
    if (!slab_test(layout_.box, rd, t0, t1)) return false;
    GridWalk walk(layout_, ray, rd, t0);
    Mailbox mailbox;
    for (;;) {
      const auto [first, count] = enter_cell<kCount>(walk, c);
      if (leaves_.template occluded_unseen<kCount>(*prims_, first, count, ray, c, mailbox)) return true;
      if (widen_near(walk.exit()) > t1 || !walk.advance(layout_, rd)) return false;
    }
  }

 protected:
  /// The reference budget (GridConfig::ref_budget): the grid of lambda, or of lambda halved until its
  /// references fit (at lambda^3 N < 1 cell a grid of one cell holds N references, which always fits).
  void do_build() override {
    const size_t n = prims_->size();
    const uint64_t max_refs = uint64_t(std::min(config_.ref_budget * double(n), 1e19));
    GridConfig config = config_;
    for (;;) {
      layout_ = make_grid_layout(prims_->bounds(), n, config);
      reach_ = 0x1p22f * insertion_margin(layout_);
      insert_all(n, max_refs);
      if (!cells_.over_budget) break;
      config.lambda *= 0.5;
    }
    leaves_.assign(*prims_, std::move(cells_.ids), config_.leaf_copies);
    cells_.ids.clear();
    this->stats_.extra["budget_exhausted"] = config.lambda != config_.lambda;
    this->stats_.extra["budget_lambda"] = config.lambda;
  }

  /// Fills the cells of layout_.
  void insert_all(size_t n, uint64_t max_refs) {
    if (layout_.cells() == 1) max_refs = UINT64_MAX;  // one cell: N references, within any budget
    if constexpr (std::is_same_v<P, TrianglePrims>) {
      // Triangles the kernel can never hit (never_hit) get no cell.
      const CellInserter voxelize = triangle_inserter(layout_, prims_->triangles());
      const P& prims = *prims_;
      const CellInserter hittable = [&prims, &voxelize](uint32_t id, std::vector<uint64_t>& out) {
        if (!never_hit(prims, id)) voxelize(id, out);
      };
      cells_ = build_grid_cells(layout_, n, hittable, max_refs);
    } else {
      std::vector<AABB> boxes(n);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) boxes[i] = prims_->bounds(i);
      });
      const P& prims = *prims_;
      cells_ = build_grid_cells(
          layout_, n,
          box_test_inserter(layout_, boxes,
                            [&prims](uint32_t i, const AABB& b) { return prims.overlaps(i, b); }),
          max_refs);
    }
  }

  void gather_stats(BuildStats& stats) const override {
    stats.primitives = prims_->size();
    gather_grid_stats(layout_, cells_, config_, stats);
    stats.bytes += leaves_.bytes();
    stats.extra["leaf_copies"] = leaves_.copied();
    stats.extra["never_hit_primitives"] = count_never_hit(*prims_);
  }

 private:
  /// True for a ray whose origin lies so far from the grid that the rounding of its walk and of the kernel
  /// (a few ulps of the origin's coordinates) may exceed the insertion margin: an origin coordinate beyond
  /// 2^22 times the margin (2-4 ulps of it fill the margin). Such a ray tests every primitive, as brute does
  /// (found by an outside check: from 1e7 away, every plane of a unit grid lies within one ulp of the
  /// origin's coordinates, and the walk took cells the kernel's hit was not in). Near the origin the margin
  /// is 2^-17 of the grid box's largest extent or coordinate, so the reach is 2^5 times that; far from it
  /// (InsertionMargin: 2^-20 of the coordinates) 4 times the coordinates.
  bool far_origin(const Ray& ray) const {
    const vec3 o = glm::abs(ray.org);
    return !(std::max({o.x, o.y, o.z}) <= reach_);
  }
  /// The walk's current cell as a range of references (first, count), counted as a node and, when it
  /// holds any, a leaf.
  template <bool kCount>
  std::pair<uint32_t, uint32_t> enter_cell(const GridWalk& walk, RayCounters& c) const {
    const size_t cell = layout_.index(walk.cell[0], walk.cell[1], walk.cell[2]);
    const uint32_t begin = cells_.offsets[cell], end = cells_.offsets[cell + 1];
    if constexpr (kCount) {
      ++c.nodes;
      if (end > begin) ++c.leaves;
    }
    return {begin, end - begin};
  }

  std::shared_ptr<const P> prims_;
  GridConfig config_;
  GridLayout layout_;
  float reach_ = 0.0f;  ///< far_origin's bound (2^22 times the layout's insertion margin)
  GridCells cells_;     ///< the cells' offsets (their ids are in leaves_)
  LeafRefs<P> leaves_;  ///< the cells' references, cell after cell, and the prepared triangles
};

}  // namespace ab
