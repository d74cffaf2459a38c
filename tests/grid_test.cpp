#include "accel/grid/grid.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>

#include "tests/structure_test_helpers.h"

namespace ab {
namespace {

using testing::adversarial_mesh;
using testing::adversarial_rays;
using testing::count_differences;
using testing::random_soup;

std::shared_ptr<const TrianglePrims> prims_of(const Mesh& m) {
  return std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(m));
}

TEST(Grid, MatchesBruteOnSoupAtSeveralDensities) {
  const Mesh mesh = random_soup(3000, 7);
  const auto rays = adversarial_rays(mesh, 3000, 11);
  for (const char* lambda : {"0.3", "1.5", "4"})
    EXPECT_EQ(count_differences("grid", mesh, rays, {{"lambda", lambda}}), 0u) << lambda;
}

TEST(Grid, MatchesBruteOnFlatAdversarialMesh) {
  const Mesh mesh = adversarial_mesh(12);
  const auto rays = adversarial_rays(mesh, 4000, 3);
  for (const char* lambda : {"0.5", "2", "6"})
    EXPECT_EQ(count_differences("grid", mesh, rays, {{"lambda", lambda}}), 0u) << lambda;
}

TEST(Grid, FlatBoundsInTwoAndThreeAxes) {
  Mesh line;  // every triangle on the x axis (degenerate, flat in y and z)
  line.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  line.triangles = {{0, 1, 2}, {1, 2, 3}};
  Mesh point;
  point.vertices = {{1, 1, 1}};
  point.triangles = {{0, 0, 0}};
  Mesh plane;  // a single axis-aligned triangle: flat in z
  plane.vertices = {{0, 0, 2}, {1, 0, 2}, {0, 1, 2}};
  plane.triangles = {{0, 1, 2}, {0, 1, 2}};
  for (const Mesh* m : {&line, &point, &plane})
    EXPECT_EQ(count_differences("grid", *m, adversarial_rays(*m, 600, 4)), 0u);
}

TEST(Grid, EmptyAndSingleTriangle) {
  Mesh one;
  one.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0.5f}};
  one.triangles = {{0, 1, 2}};
  EXPECT_EQ(count_differences("grid", Mesh{}, adversarial_rays(Mesh{}, 50, 1)), 0u);
  EXPECT_EQ(count_differences("grid", one, adversarial_rays(one, 300, 2)), 0u);
}

TEST(Grid, ResolutionFollowsExtentAndCap) {
  GridConfig config;
  config.lambda = 1.0;
  const GridLayout cube = make_grid_layout({{0, 0, 0}, {1, 1, 1}}, 1000, config);
  EXPECT_EQ(cube.res[0], 10);
  EXPECT_EQ(cube.res[1], 10);
  EXPECT_EQ(cube.res[2], 10);
  const GridLayout slab = make_grid_layout({{0, 0, 0}, {4, 1, 0}}, 400, config);  // flat: a 2D grid
  EXPECT_EQ(slab.res[2], 1);
  EXPECT_EQ(slab.res[0], 40);
  EXPECT_EQ(slab.res[1], 10);
  const GridLayout thin = make_grid_layout({{0, 0, 0}, {100, 100, 0.001f}}, 10000, config);
  EXPECT_EQ(thin.res[2], 1);
  EXPECT_EQ(thin.res[0], 100);
  config.max_cells = 64;
  EXPECT_LE(make_grid_layout({{0, 0, 0}, {1, 1, 1}}, 100000, config).cells(), 64u);
}

TEST(Grid, ExactInsertionBeatsBoundsInsertion) {
  // A long diagonal triangle: its bounds cover the whole grid, but it overlaps only cells near the diagonal.
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 1, 1}, {1.0f, 1.0f, 0.98f}, {0, 0, 1}, {0.01f, 0, 1}, {0, 0.01f, 1}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  Params params = testing::make_params({{"lambda", "8"}, {"max_cells", "1000"}});
  Grid<TrianglePrims> grid(prims_of(m), GridConfig::read(params));
  grid.build();
  const size_t cells = grid.layout().cells();
  EXPECT_GT(cells, 100u);
  EXPECT_LT(grid.stats().references, cells / 4);
  EXPECT_EQ(count_differences("grid", m, adversarial_rays(m, 500, 8), {{"lambda", "8"}}), 0u);
}

/// Cells of mesh at density lambda from the voxelizer and from the generic exact test per cell.
std::pair<GridCells, GridCells> both_insertions(const Mesh& mesh, double lambda) {
  const TrianglePrims prims(std::make_shared<const Mesh>(mesh));
  GridConfig config;
  config.lambda = lambda;
  const GridLayout layout = make_grid_layout(prims.bounds(), prims.size(), config);
  std::vector<AABB> boxes;
  for (size_t i = 0; i < prims.size(); ++i) boxes.push_back(prims.bounds(i));
  GridCells voxelized = build_grid_cells(layout, prims.size(), triangle_inserter(layout, prims.triangles()));
  GridCells tested = build_grid_cells(
      layout, prims.size(),
      box_test_inserter(layout, boxes, [&](uint32_t i, const AABB& b) { return prims.overlaps(i, b); }));
  return {std::move(voxelized), std::move(tested)};
}

TEST(Grid, VoxelizationKeepsEveryCellOfTheExactTest) {
  Mesh diagonal;  // long thin triangles across many cells, one lying in a cell plane
  diagonal.vertices = {{0, 0, 0},     {1, 1, 1},    {1.0f, 1.0f, 0.98f}, {0, 0, 1},   {0.01f, 0, 1},
                       {0, 0.01f, 1}, {0, 0.5f, 0}, {1, 0.5f, 0},        {1, 0.5f, 1}};
  diagonal.triangles = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  const Mesh meshes[] = {random_soup(3000, 41, 0.1f), random_soup(500, 42, 0.6f), adversarial_mesh(12),
                         diagonal};
  for (const Mesh& mesh : meshes) {
    for (double lambda : {0.5, 2.0, 5.0}) {
      const auto [voxelized, tested] = both_insertions(mesh, lambda);
      size_t lost = 0;
      for (size_t c = 0; c + 1 < tested.offsets.size(); ++c) {
        const auto t0 = tested.ids.begin() + tested.offsets[c],
                   t1 = tested.ids.begin() + tested.offsets[c + 1];
        const auto v0 = voxelized.ids.begin() + voxelized.offsets[c],
                   v1 = voxelized.ids.begin() + voxelized.offsets[c + 1];
        lost += !std::includes(v0, v1, t0, t1);
      }
      EXPECT_EQ(lost, 0u) << "lambda " << lambda;
      EXPECT_GE(voxelized.ids.size(), tested.ids.size());
      EXPECT_LE(voxelized.ids.size(), tested.ids.size() * 103 / 100 + 8)
          << "lambda " << lambda;  // only the margin's extra
    }
  }
}

TEST(Grid, CellsAreDeterministicAndSorted) {
  const Mesh mesh = random_soup(20000, 3, 0.03f);
  auto build_in = [&](int threads) {
    tbb::task_arena arena(threads);
    auto grid = std::make_unique<Grid<TrianglePrims>>(prims_of(mesh), GridConfig{});
    arena.execute([&] { grid->build(); });
    return grid;
  };
  const auto one = build_in(1), two = build_in(2);
  EXPECT_EQ(one->cells().offsets, two->cells().offsets);
  EXPECT_EQ(one->ids(), two->ids());
  const auto& c = one->cells();
  const auto& ids = one->ids();
  for (size_t k = 0; k + 1 < c.offsets.size(); ++k)
    for (uint32_t i = c.offsets[k] + 1; i < c.offsets[k + 1]; ++i) ASSERT_LT(ids[i - 1], ids[i]);
  EXPECT_GT(one->stats().references, mesh.size());
  // The prepared triangles: one per reference when copied into cell order, else one per triangle.
  const size_t prepared = one->stats().extra.at("leaf_copies").get<bool>() ? ids.size() : mesh.size();
  EXPECT_EQ(one->stats().bytes, (c.offsets.size() + ids.size()) * 4 + prepared * sizeof(PreparedTriangle));
}

TEST(Grid, MailboxSkipsAreCounted) {
  // Large triangles spanning many cells: rays along them meet each triangle in several cells.
  const Mesh mesh = random_soup(200, 21, 0.3f);
  const auto rays = adversarial_rays(mesh, 500, 22);
  auto grid = make_accelerator("grid", prims_of(mesh), testing::make_params({{"lambda", "4"}}));
  grid->build();
  std::vector<Hit> hits(rays.size());
  RayCounters c;
  grid->intersect_counted(rays, hits, c);
  EXPECT_GT(c.mailbox_skips, 0u);
  EXPECT_GT(c.nodes, c.leaves / 2);
  EXPECT_EQ(count_differences("grid", mesh, rays, {{"lambda", "4"}}), 0u);
}

TEST(Grid, MailboxRemembersAndForgetsOnlyByCollision) {
  Mailbox mb;
  EXPECT_FALSE(mb.seen(5));
  EXPECT_TRUE(mb.seen(5));
  EXPECT_FALSE(mb.seen(5 + 64));  // same slot: evicts 5
  EXPECT_FALSE(mb.seen(5));
  EXPECT_FALSE(mb.seen(6));
  EXPECT_TRUE(mb.seen(6));
}

TEST(Grid, RejectsBadParams) {
  const auto prims = prims_of(random_soup(10, 1));
  EXPECT_THROW(make_accelerator("grid", prims, testing::make_params({{"lambda", "0"}})), ParamError);
  EXPECT_THROW(make_accelerator("grid", prims, testing::make_params({{"bins", "4"}})), ParamError);
  EXPECT_THROW(make_accelerator("grid", prims, testing::make_params({{"max_cells", "-1"}})), ParamError);
}

TEST(Grid, TopLevelOverInstances) {
  const Mesh mesh = random_soup(300, 29, 0.1f);
  const auto inst = testing::make_instances(mesh, "grid", 9);
  const AABB b = inst->bounds();
  Mesh box_mesh;
  box_mesh.vertices = {b.lo, b.hi, 0.5f * (b.lo + b.hi)};
  box_mesh.triangles = {{0, 1, 2}};
  EXPECT_EQ(testing::count_instance_differences("grid", inst, adversarial_rays(box_mesh, 1500, 31)), 0u);
}

}  // namespace
}  // namespace ab
