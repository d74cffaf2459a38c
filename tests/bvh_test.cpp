#include "accel/bvh/bvh.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cstring>

#include "accel/bvh/sah_split.h"
#include "accel/common/sah.h"
#include "tests/structure_test_helpers.h"

namespace ab {
namespace {

using testing::adversarial_mesh;
using testing::adversarial_rays;
using testing::count_differences;
using testing::random_soup;

const char* const kBvhs[] = {"bvh-median", "bvh-sah", "bvh-sweep"};

std::shared_ptr<const TrianglePrims> prims_of(const Mesh& m) {
  return std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(m));
}

TEST(Bvh, MatchesBruteOnSoup) {
  const Mesh mesh = random_soup(3000, 7);
  const auto rays = adversarial_rays(mesh, 3000, 11);
  for (const char* name : kBvhs) EXPECT_EQ(count_differences(name, mesh, rays), 0u) << name;
}

TEST(Bvh, MatchesBruteOnAdversarialMesh) {
  const Mesh mesh = adversarial_mesh(12);
  const auto rays = adversarial_rays(mesh, 4000, 3);
  for (const char* name : kBvhs) {
    EXPECT_EQ(count_differences(name, mesh, rays), 0u) << name;
    EXPECT_EQ(count_differences(name, mesh, rays, {{"max_depth", "2"}}), 0u) << name << " depth-limited";
  }
  EXPECT_EQ(count_differences("bvh-sah", mesh, rays, {{"bins", "2"}, {"max_leaf_size", "1"}}), 0u);
  EXPECT_EQ(count_differences("bvh-sah", mesh, rays, {{"width", "2"}}), 0u) << "binary bvh-sah";
  EXPECT_EQ(count_differences("bvh-median", mesh, rays, {{"width", "8"}}), 0u) << "wide bvh-median";
}

TEST(Bvh, EmptyAndSingleTriangle) {
  Mesh one;
  one.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.triangles = {{0, 1, 2}};
  for (const char* name : kBvhs) {
    EXPECT_EQ(count_differences(name, Mesh{}, adversarial_rays(Mesh{}, 50, 1)), 0u) << name;
    EXPECT_EQ(count_differences(name, one, adversarial_rays(one, 200, 2)), 0u) << name;
  }
  auto bvh = make_accelerator("bvh-sah", prims_of(Mesh{}), Params());
  bvh->build();
  EXPECT_EQ(bvh->stats().nodes, 0u);
  Ray r;
  r.org = {0.25f, 0.25f, 1.0f};
  r.dir = {0, 0, -1};
  Hit h;
  bvh->intersect_one(r, h, kInvalidId, nullptr);
  EXPECT_FALSE(h.found());
}

TEST(Bvh, AllDuplicatesSplitsToLeafSize) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles.assign(100, {0, 1, 2});
  for (const char* name : kBvhs) {
    EXPECT_EQ(count_differences(name, m, adversarial_rays(m, 300, 5)), 0u) << name;
    auto bvh = make_accelerator(name, prims_of(m), Params());
    bvh->build();
    EXPECT_LE(bvh->stats().leaf_size_histogram.rbegin()->first, 8u) << name;
  }
}

/// Structural invariants: depth-first layout, children inside parents, leaves cover a permutation.
template <template <class> class S>
void check_structure(const Mesh& mesh) {
  Params params = testing::make_params({{"width", "2"}});
  S<TrianglePrims> bvh(prims_of(mesh), S<TrianglePrims>::Config::read(params));
  bvh.build();
  const auto& nodes = bvh.nodes();
  ASSERT_FALSE(nodes.empty());
  std::vector<int> seen(mesh.size(), 0);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(nodes.data()) % 64, 0u);
  for (size_t i = 0; i < nodes.size(); ++i) {
    if (i == 1) continue;  // padding
    const AABB box = nodes[i].box();
    if (nodes[i].is_leaf()) {
      for (uint32_t k = nodes[i].offset; k < nodes[i].offset + nodes[i].count; ++k) {
        const uint32_t id = bvh.order()[k];
        ++seen[id];
        const AABB tb = mesh.triangle(id).bounds();
        EXPECT_TRUE(box.contains(tb.lo) && box.contains(tb.hi));
      }
      continue;
    }
    ASSERT_LT(nodes[i].offset + 1, nodes.size());
    ASSERT_GT(nodes[i].offset, i);
    ASSERT_EQ(nodes[i].offset % 2, 0u);  // sibling pairs share a 64-byte line
    for (const BvhNode* child : {&nodes[nodes[i].offset], &nodes[nodes[i].offset + 1]}) {
      EXPECT_TRUE(box.contains(child->box().lo) && box.contains(child->box().hi));
    }
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int s) { return s == 1; }));
  EXPECT_EQ(bvh.stats().nodes + 1, nodes.size());
  EXPECT_EQ(bvh.stats().references, mesh.size());
  EXPECT_EQ(bvh.stats().nodes, 2 * bvh.stats().leaves - 1);
  EXPECT_GT(bvh.stats().sah_cost, 0.0);
  EXPECT_GE(bvh.stats().bytes, nodes.size() * 32);
}

TEST(Bvh, StructureInvariants) {
  const Mesh mesh = random_soup(2000, 5);
  check_structure<BvhMedian>(mesh);
  check_structure<BvhSah>(mesh);
  check_structure<BvhSweep>(mesh);
}

TEST(Bvh, MedianLeafSizeIsRespected) {
  const Mesh mesh = random_soup(1000, 9);
  auto bvh = make_accelerator("bvh-median", prims_of(mesh), testing::make_params({{"leaf_size", "3"}}));
  bvh->build();
  EXPECT_LE(bvh->stats().leaf_size_histogram.rbegin()->first, 3u);
  EXPECT_LE(bvh->stats().max_depth, 10u);  // balanced: ceil(log2(1000 / 3)) + 1
}

TEST(Bvh, BinnedSahIsCloseToSweepAndBetterThanMedian) {
  const Mesh mesh = random_soup(20000, 13, 0.02f);
  auto cost = [&](const char* name) {  // binary trees priced per triangle, as the sweep's
    auto bvh = make_accelerator(name, prims_of(mesh), testing::make_params({{"width", "2"}}));
    bvh->build();
    return bvh->stats().sah_cost;
  };
  const double median = cost("bvh-median"), binned = cost("bvh-sah"), sweep = cost("bvh-sweep");
  EXPECT_LT(binned, sweep * 1.05);
  EXPECT_LT(sweep, median);
}

TEST(Bvh, SameTreeForAnyThreadCount) {
  const Mesh mesh = random_soup(150000, 17, 0.01f);  // above the parallel thresholds
  for (const char* width : {"2", "8"}) {
    auto build_in = [&](int threads) {
      tbb::task_arena arena(threads);
      Params params = testing::make_params({{"width", width}});
      auto bvh = std::make_unique<BvhSah<TrianglePrims>>(prims_of(mesh),
                                                         BvhSah<TrianglePrims>::Config::read(params));
      arena.execute([&] { bvh->build(); });
      return bvh;
    };
    const auto one = build_in(1), two = build_in(2);
    ASSERT_FALSE(one->nodes().empty() && one->wide_nodes().empty()) << width;
    ASSERT_EQ(one->nodes().size(), two->nodes().size());
    EXPECT_EQ(std::memcmp(one->nodes().data(), two->nodes().data(), one->nodes().size() * sizeof(BvhNode)),
              0);
    ASSERT_EQ(one->wide_nodes().size(), two->wide_nodes().size());
    EXPECT_EQ(std::memcmp(one->wide_nodes().data(), two->wide_nodes().data(),
                          one->wide_nodes().size() * sizeof(Bvh8Node)),
              0);
    EXPECT_EQ(one->order(), two->order());
    EXPECT_EQ(one->block_ids(), two->block_ids());
  }
}

TEST(Bvh, CountersAreFilledOnlyByTheCountingPass) {
  const Mesh mesh = random_soup(500, 19);
  const auto rays = adversarial_rays(mesh, 200, 23);
  auto bvh = make_accelerator("bvh-sah", prims_of(mesh), Params());
  bvh->build();
  std::vector<Hit> hits(rays.size());
  RayCounters c;
  bvh->intersect_counted(rays, hits, c);
  EXPECT_GT(c.nodes, 0u);
  EXPECT_GT(c.leaves, 0u);
  EXPECT_GT(c.prims, 0u);
  EXPECT_LT(c.prims, rays.size() * mesh.size() / 4);  // far fewer tests than brute force
}

TEST(Bvh, RejectsBadParams) {
  const auto prims = prims_of(random_soup(10, 1));
  EXPECT_THROW(make_accelerator("bvh-sah", prims, testing::make_params({{"bins", "1"}})), ParamError);
  EXPECT_THROW(make_accelerator("bvh-sah", prims, testing::make_params({{"leaf_size", "4"}})), ParamError);
  EXPECT_THROW(make_accelerator("bvh-median", prims, testing::make_params({{"max_depth", "0"}})), ParamError);
  EXPECT_THROW(make_accelerator("bvh-sweep", prims, testing::make_params({{"bins", "8"}})), ParamError);
  EXPECT_NO_THROW(
      make_accelerator("bvh-sah", prims, testing::make_params({{"bins", "32"}, {"traversal_cost", "0.5"}})));
}

TEST(Bvh, TopLevelOverInstances) {
  const Mesh mesh = random_soup(300, 29, 0.1f);
  const auto inst = testing::make_instances(mesh, "bvh-sah", 7);
  AABB b = inst->bounds();
  Mesh box_mesh;  // only for ray placement
  box_mesh.vertices = {b.lo, b.hi, 0.5f * (b.lo + b.hi)};
  box_mesh.triangles = {{0, 1, 2}};
  const auto rays = adversarial_rays(box_mesh, 1500, 31);
  for (const char* name : kBvhs) EXPECT_EQ(testing::count_instance_differences(name, inst, rays), 0u) << name;
}

/// One bin of Wald's binned builder: the bounds of the primitives whose centroid fell in it, and their count.
struct SahBin {
  AABB bounds;
  uint32_t count = 0;

  /// Adds a primitive with bounds b.
  void add(const AABB& b) {
    bounds.extend(b);
    ++count;
  }
};

/// The scalar form of the binned builder's split search over one axis (Wald 2007), the reference its
/// three-axis SIMD form follows: suffix areas right to left, then every boundary left to right, ranked by
/// left_area * left_count + right_area * right_count; the cheapest is priced with SahCosts::split and
/// replaces best when cheaper.
void best_bin_split(const SahBin* bins, int n, int axis, float parent_area, const SahCosts& costs,
                    SahSplit& best) {
  std::array<float, 256> right_area;
  std::array<uint32_t, 256> right_count;
  AABB acc;
  uint32_t cnt = 0;
  for (int i = n - 1; i > 0; --i) {
    acc.extend(bins[i].bounds);
    cnt += bins[i].count;
    right_area[i] = acc.area();
    right_count[i] = cnt;
  }
  acc = AABB{};
  cnt = 0;
  float best_weighted = kInf, best_left_area = 0.0f, best_right_area = 0.0f;
  int best_i = 0;
  uint32_t best_left = 0;
  for (int i = 1; i < n; ++i) {
    acc.extend(bins[i - 1].bounds);
    cnt += bins[i - 1].count;
    if (cnt == 0 || right_count[i] == 0) continue;
    const float left_area = acc.area();
    const float weighted = left_area * float(cnt) + right_area[i] * float(right_count[i]);
    if (weighted < best_weighted) {
      best_weighted = weighted, best_i = i, best_left = cnt;
      best_left_area = left_area, best_right_area = right_area[i];
    }
  }
  if (best_i == 0) return;
  const float c = costs.split(parent_area, best_left_area, best_left, best_right_area, right_count[best_i]);
  if (c < best.cost) best = {axis, best_i, c};
}

TEST(Sah, BinSplitFindsTheGap) {
  // Two clusters: bins 0-1 and 6-7; the best boundary lies between them.
  std::vector<SahBin> bins(8);
  bins[0].add({{0, 0, 0}, {1, 1, 1}});
  bins[1].add({{1, 0, 0}, {2, 1, 1}});
  bins[6].add({{6, 0, 0}, {7, 1, 1}});
  bins[7].add({{7, 0, 0}, {8, 1, 1}});
  SahSplit best;
  best_bin_split(bins.data(), 8, 0, AABB{{0, 0, 0}, {8, 1, 1}}.area(), kUnitSahCosts, best);
  EXPECT_EQ(best.axis, 0);
  EXPECT_GE(best.position, 2);
  EXPECT_LE(best.position, 6);
  EXPECT_LT(best.cost, kUnitSahCosts.leaf(4));
}

}  // namespace
}  // namespace ab
