// The 8-wide BVH: its SIMD box test against the scalar one (and against the binary walk's arithmetic), the
// four-lane kernel against the scalar kernel (bit for bit), the collapsed tree's invariants and its thread
// independence.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>

#include "accel/bvh/bvh.h"
#include "accel/bvh/leaf_fill.h"
#include "accel/bvh/walk8.h"
#include "accel/core/box_test.h"
#include "accel/core/triangle4.h"
#include "tests/structure_test_helpers.h"

namespace ab {
namespace {

using testing::adversarial_mesh;
using testing::adversarial_rays;
using testing::random_soup;
using testing::uniform;

std::shared_ptr<const TrianglePrims> prims_of(const Mesh& m) {
  return std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(m));
}

/// Lane k of node holds no child (an empty box).
void set_empty_lane(Bvh8Node& node, int k) {
  for (int a = 0; a < 3; ++a) node.bounds[a][k] = kInf, node.bounds[3 + a][k] = -kInf;
  node.child[k] = node.count[k] = 0;
}

/// Lane k of node holds the leaf [first, first + n) of the order in box.
void set_leaf_lane(Bvh8Node& node, int k, const AABB& box, uint32_t first, uint32_t n) {
  for (int a = 0; a < 3; ++a) node.bounds[a][k] = box.lo[a], node.bounds[3 + a][k] = box.hi[a];
  node.child[k] = first;
  node.count[k] = n;
}

uint32_t bits(float f) {
  return std::bit_cast<uint32_t>(f);
}

/// Random rays with awkward directions: zero and -0 components, axis-parallel, tiny and huge.
Ray awkward_ray(std::mt19937& rng) {
  Ray r;
  r.org = {uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -2, 2)};
  for (int a = 0; a < 3; ++a) {
    const uint32_t pick = rng() % 8;
    r.dir[a] = pick == 0 ? 0.0f : pick == 1 ? -0.0f : pick == 2 ? 1e-30f : uniform(rng, -1, 1);
    if (rng() % 6 == 0) r.org[a] = std::round(r.org[a]);  // origin on a box plane
  }
  r.tmin = rng() % 4 == 0 ? uniform(rng, 0, 1) : 0.0f;
  r.tmax = rng() % 4 == 0 ? uniform(rng, 0, 3) : kInf;
  return r;
}

TEST(Bvh8, SimdBoxTestEqualsTheScalarOneLaneByLane) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20000; ++trial) {
    Bvh8Node node;
    for (int k = 0; k < 8; ++k) {
      const bool empty = rng() % 7 == 0;
      for (int a = 0; a < 3; ++a) {
        float lo = std::round(uniform(rng, -2, 2) * 4) / 4,
              hi = lo + (rng() % 3 == 0 ? 0.0f : uniform(rng, 0, 2));
        node.bounds[a][k] = empty ? kInf : lo;
        node.bounds[3 + a][k] = empty ? -kInf : hi;
      }
      node.child[k] = node.count[k] = 0;
    }
    const Ray ray = awkward_ray(rng);
    const Bvh8RayTest test(ray);
    const float limit =
        rng() % 2 ? ray.tmax : std::min(ray.tmax, uniform(rng, 0, 2));  // as the walk passes it
    alignas(32) float simd[8], scalar[8];
    const unsigned m1 = test.entries(node, limit, simd), m2 = test.entries_scalar(node, limit, scalar);
    ASSERT_EQ(m1, m2) << "trial " << trial;
    for (int k = 0; k < 8; ++k) {
      if (m1 >> k & 1) {
        ASSERT_EQ(bits(simd[k]) & 0x7fffffffu, bits(scalar[k]) & 0x7fffffffu) << trial;
      }
      // A lane entered by the wide test is entered by the binary test's arithmetic too.
      if (!node.used(k)) {
        EXPECT_FALSE(m1 >> k & 1);
      }
      // The general arithmetic's verdict (the binary walk's); the folded path (tmin >= 0) may differ only
      // where the widened interval is empty or not by a rounding of its ends (an ulp of a 256-ulp margin).
      float t0 = ray.tmin, t1 = limit;
      const bool general = node.used(k) && slab_test(node.box(k), RayBoxData(ray), t0, t1);
      if (test.folded && general != bool(m1 >> k & 1) && node.used(k)) {
        EXPECT_LE(std::fabs(t0 - t1), 0x1p-20f * std::max(std::fabs(t0), std::fabs(t1))) << trial;
        continue;
      }
      ASSERT_EQ(bool(m1 >> k & 1), general)
          << trial << " lane " << k << " org " << ray.org.x << "," << ray.org.y << "," << ray.org.z << " dir "
          << ray.dir.x << "," << ray.dir.y << "," << ray.dir.z << " t " << ray.tmin << ".." << ray.tmax
          << " limit " << limit << " box " << node.box(k).lo.x << "," << node.box(k).lo.y << ","
          << node.box(k).lo.z << " - " << node.box(k).hi.x << "," << node.box(k).hi.y << ","
          << node.box(k).hi.z << " entry " << simd[k];
    }
  }
}

TEST(Bvh8, EnteredChildrenAreRankedFarthestFirst) {
  std::mt19937 rng(8);
  Bvh8Node node{};
  for (int k = 0; k < 8; ++k) node.child[k] = uint32_t(100 + k), node.count[k] = uint32_t(k % 3);
  for (int trial = 0; trial < 20000; ++trial) {
    unsigned mask = rng() & 0xffu;
    if (std::popcount(mask) < 2) mask |= 3u << (rng() % 7);
    alignas(32) float t[8];
    for (float& x : t) x = rng() % 5 == 0 ? 1.0f : rng() % 9 == 0 ? kInf : uniform(rng, 0, 4);  // ties too
    Bvh8StackEntry items[8];
    const int m = rank_entered_children(node, mask, t, items);
    ASSERT_EQ(m, std::popcount(mask));
    unsigned seen = 0;
    for (int j = 0; j < m; ++j) {
      const unsigned lane = items[j].child - 100;
      ASSERT_TRUE(mask >> lane & 1) << trial;
      seen |= 1u << lane;
      EXPECT_EQ(items[j].count, lane % 3);
      EXPECT_EQ(bits(items[j].t), bits(t[lane]));
      // nearest last (distances within the key's three dropped low bits count as ties)
      if (j > 0) {
        EXPECT_GE(bits(items[j - 1].t) & ~7u, bits(items[j].t) & ~7u) << trial;
      }
    }
    EXPECT_EQ(seen, mask) << trial;  // every entered lane exactly once
  }
}

TEST(Bvh8, StackedChildrenComeBackNearestFirst) {
  // stack_entered_children returns one entered child and stacks the others: sorted, the returned one is the
  // nearest and the stack pops the rest nearer first; unsorted, every entered lane once. Two children take
  // their own path (one compare), more the ranking.
  std::mt19937 rng(11);
  Bvh8Node node{};
  for (int k = 0; k < 8; ++k) node.child[k] = uint32_t(100 + k), node.count[k] = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    unsigned mask = rng() & 0xffu;
    if (trial % 2 == 0) mask = (1u << (rng() % 8)) | (1u << (rng() % 8));  // two lanes often
    if (std::popcount(mask) < 2) mask |= 3u << (rng() % 7);
    alignas(32) float t[8];
    for (float& x : t) x = rng() % 5 == 0 ? 1.0f : uniform(rng, 0, 4);  // ties too
    for (const bool sorted : {true, false}) {
      Bvh8Stack stack;
      const Bvh8StackEntry next =
          sorted ? stack_entered_children<true>(&node, node, mask, t, stack, nullptr, 0)
                 : stack_entered_children<false>(&node, node, mask, t, stack, nullptr, 0);
      unsigned seen = 1u << (next.child - 100);
      float last = next.t;
      for (Bvh8StackEntry e; stack.pop(kInf, e);) {
        const unsigned lane = e.child - 100;
        ASSERT_FALSE(seen >> lane & 1) << trial;
        seen |= 1u << lane;
        EXPECT_EQ(bits(e.t), bits(t[lane]));
        if (sorted) {  // within the ranking key's three dropped low bits distances count as ties
          EXPECT_LE(bits(last) & ~7u, bits(e.t) & ~7u) << trial;
        }
        last = e.t;
      }
      EXPECT_EQ(seen, mask) << trial;
    }
  }
}

TEST(Bvh8, FourLaneKernelGivesTheScalarKernelsBits) {
  const Mesh mesh = adversarial_mesh(6);
  std::vector<Triangle> tris;
  for (size_t i = 0; i < mesh.size(); ++i) tris.push_back(mesh.triangle(i));
  const Mesh soup = random_soup(400, 5, 0.5f);
  for (size_t i = 0; i < soup.size(); ++i) tris.push_back(soup.triangle(i));
  std::vector<Ray> rays = adversarial_rays(mesh, 1500, 9);
  const auto more = adversarial_rays(soup, 1500, 10);
  rays.insert(rays.end(), more.begin(), more.end());
  size_t hits = 0;
  for (size_t first = 0; first < tris.size(); first += 3) {  // overlapping groups, the last one partial
    const size_t n = std::min<size_t>(4, tris.size() - first);
    const Triangle4 quad = Triangle4::pack(std::span<const Triangle>(tris.data() + first, n));
    for (size_t r = first % 7; r < rays.size(); r += 5) {
      const RayBoxData box(rays[r]);
      const Ray4 ray4(rays[r], box);
      alignas(16) float t[4], u[4], v[4];
      const unsigned mask = intersect_triangle4(ray4, quad, t, u, v);
      for (size_t j = 0; j < 4; ++j) {
        TriangleHit th{};
        const bool scalar = j < n && intersect_triangle(rays[r], tris[first + j], th);
        ASSERT_EQ(bool(mask >> j & 1), scalar) << "triangle " << first + j << " ray " << r;
        if (!scalar) continue;
        ++hits;
        EXPECT_EQ(bits(t[j]), bits(th.t));
        EXPECT_EQ(bits(u[j]), bits(th.u));
        EXPECT_EQ(bits(v[j]), bits(th.v));
      }
    }
  }
  EXPECT_GT(hits, 1000u);  // the comparison saw real hits
}

/// Invariants of the collapsed tree: lanes hold boxes that contain their children's boxes or their
/// triangles, every triangle sits in exactly one block lane, nodes have 2..8 children.
TEST(Bvh8, CollapsedTreeInvariants) {
  const Mesh mesh = random_soup(5000, 21);
  BvhSah<TrianglePrims> bvh(prims_of(mesh), BvhSahConfig{});
  bvh.build();
  const auto& wide = bvh.wide_nodes();
  ASSERT_FALSE(wide.empty());
  EXPECT_TRUE(bvh.nodes().empty());  // the binary tree is freed
  EXPECT_EQ(reinterpret_cast<uintptr_t>(wide.data()) % 64, 0u);
  std::vector<int> seen(mesh.size(), 0);
  uint64_t lanes = 0, leaves = 0;
  for (size_t i = 0; i < wide.size(); ++i) {
    int used = 0;
    for (int k = 0; k < 8; ++k) {
      if (!wide[i].used(k)) continue;
      ++used;
      const AABB box = wide[i].box(k);
      if (wide[i].count[k] == 0) {
        const uint32_t c = wide[i].child[k];
        ASSERT_GT(c, i);
        ASSERT_LT(c, wide.size());
        for (int j = 0; j < 8; ++j)
          if (wide[c].used(j)) {
            ASSERT_TRUE(box.contains(wide[c].box(j).lo) && box.contains(wide[c].box(j).hi));
          }
        continue;
      }
      ++leaves;
      for (uint32_t s = 0; s < wide[i].count[k]; ++s) {
        const uint32_t id = bvh.block_ids()[4 * wide[i].child[k] + s];
        ASSERT_LT(id, mesh.size());
        ++seen[id];
        const AABB tb = mesh.triangle(id).bounds();
        EXPECT_TRUE(box.contains(tb.lo) && box.contains(tb.hi));
      }
    }
    EXPECT_GE(used, i == 0 ? 1 : 2);
    lanes += uint64_t(used);
    for (int k = 0; k < 8 && used < 8; ++k)  // free lanes took the leaves of two blocks (leaf_fill.h)
      EXPECT_TRUE(wide[i].count[k] <= 4 || wide[i].count[k] > 8) << "node " << i << " lane " << k;
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int s) { return s == 1; }));
  EXPECT_EQ(bvh.stats().leaves, leaves);
  EXPECT_EQ(bvh.stats().nodes, wide.size() + leaves);
  EXPECT_EQ(bvh.stats().references, mesh.size());
  EXPECT_GT(double(lanes) / double(wide.size()), 3.0);  // the collapse fills nodes
  EXPECT_LT(bvh.stats().max_depth, bvh.stats().extra["binary_max_depth"].get<uint32_t>());
}

/// fill_free_lanes on one node: a leaf of n (5 to 8) triangles beside a free lane becomes two leaves of at
/// most four whose boxes hold their triangles' parts in the old box and lie inside it; a full node and
/// leaves of one block stay as they are.
TEST(Bvh8, FreeLanesTakeTheTwoBlockLeaves) {
  const Mesh mesh = random_soup(64, 5);
  const auto prims = prims_of(mesh);
  std::vector<uint32_t> order(mesh.size());
  std::iota(order.begin(), order.end(), 0u);
  for (uint32_t n = 5; n <= 8; ++n) {
    Bvh8Node node{};
    for (int k = 0; k < 8; ++k) set_empty_lane(node, k);
    AABB leaf;  // the centres' box: every triangle has a part inside, as in a spatial-split leaf
    for (uint32_t j = 0; j < n; ++j) leaf.extend(mesh.triangle(j).bounds().center());
    set_leaf_lane(node, 0, leaf, 0, n);
    set_leaf_lane(node, 1, mesh.triangle(10).bounds(), 10, 3);
    NodeLaneIds ids;
    fill_free_lanes(node, order, *prims, ids);
    ASSERT_EQ(node.count[1], 3u);
    ASSERT_EQ(ids.lane[1], order.data() + 10);
    ASSERT_TRUE(node.used(2));
    EXPECT_EQ(node.count[0] + node.count[2], n);
    EXPECT_LE(node.count[0], 4u);
    EXPECT_LE(node.count[2], 4u);
    EXPECT_FALSE(node.used(3));
    std::vector<uint32_t> got;
    for (int k : {0, 2}) {
      const AABB box = node.box(k);
      EXPECT_TRUE(leaf.contains(box.lo) && leaf.contains(box.hi));
      for (uint32_t j = 0; j < node.count[k]; ++j) {
        got.push_back(ids.lane[k][j]);
        const AABB part = AABB::intersection(mesh.triangle(ids.lane[k][j]).bounds(), leaf);
        EXPECT_TRUE(box.contains(part.lo) && box.contains(part.hi));
      }
    }
    std::sort(got.begin(), got.end());
    for (uint32_t j = 0; j < n; ++j) EXPECT_EQ(got[j], j);
  }
  Bvh8Node full{};
  for (int k = 0; k < 8; ++k) set_leaf_lane(full, k, mesh.triangle(k).bounds(), 8 * k, 6);
  NodeLaneIds ids;
  fill_free_lanes(full, order, *prims, ids);
  for (int k = 0; k < 8; ++k) EXPECT_EQ(full.count[k], 6u);
}

TEST(Bvh8, WidthIsTwoOrEight) {
  const auto prims = prims_of(random_soup(10, 1));
  EXPECT_THROW(make_accelerator("bvh-sah", prims, testing::make_params({{"width", "4"}})), ParamError);
  EXPECT_THROW(make_accelerator("bvh-sah", prims, testing::make_params({{"width", "16"}})), ParamError);
  auto two = make_accelerator("bvh-sah", prims, testing::make_params({{"width", "2"}}));
  two->build();
  EXPECT_EQ(two->stats().extra["width"], 2);
  auto eight = make_accelerator("bvh-sah", prims, Params());
  eight->build();
  EXPECT_EQ(eight->stats().extra["width"], 8);
}

}  // namespace
}  // namespace ab
