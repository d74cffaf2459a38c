// k-d trees (kdtree-median, kdtree-sah): node encoding, the plane step, flat geometry lying in split
// planes, rays lying in split planes, statistics, thread-count independence, kdtree-sah's binned nodes and
// parameter checks.
#include "accel/kdtree/kdtree.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "accel/common/depth_limit.h"
#include "accel/common/empty_leaves.h"
#include "accel/common/split_plane.h"
#include "accel/kdtree/node.h"
#include "datasets/generators.h"
#include "structure_test_helpers.h"

namespace ab {
namespace {

using testing::adversarial_mesh;
using testing::adversarial_rays;
using testing::count_differences;
using testing::random_soup;
using testing::uniform;

const char* const kKdNames[] = {"kdtree-median", "kdtree-sah"};

/// k x k quads on each of the planes x = i / k, y = i / k and z = i / k (i = 0..k): flat geometry on the
/// coordinates where median and SAH planes fall.
Mesh axis_planes(int k) {
  Mesh m;
  for (int axis = 0; axis < 3; ++axis)
    for (int i = 0; i <= k; i += 2) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
          const uint32_t base = uint32_t(m.vertices.size());
          for (int c = 0; c < 4; ++c) {
            vec3 p(0.0f);
            p[axis] = float(i) / float(k);
            p[u] = float(a + (c == 1 || c == 2)) / float(k);
            p[v] = float(b + (c >= 2)) / float(k);
            m.vertices.push_back(p);
          }
          m.triangles.push_back({base, base + 1, base + 2});
          m.triangles.push_back({base, base + 2, base + 3});
        }
    }
  return m;
}

/// Rays lying in the planes x, y or z = i / k (a zero direction component on that axis), starting
/// outside or on the geometry, plus rays along the lines where two planes meet.
std::vector<Ray> in_plane_rays(int k, size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Ray> rays;
  for (size_t n = 0; n < count; ++n) {
    Ray r;
    const int axis = int(n % 3);
    r.org = {uniform(rng, -0.5f, 1.5f), uniform(rng, -0.5f, 1.5f), uniform(rng, -0.5f, 1.5f)};
    r.org[axis] = float(rng() % (k + 1)) / float(k);
    r.dir = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
    r.dir[axis] = (n % 5 == 4) ? -0.0f : 0.0f;
    if (n % 4 == 3) {  // along an edge line: two coordinates on planes, one direction component
      const int b = (axis + 1) % 3;
      r.org[b] = float(rng() % (k + 1)) / float(k);
      r.dir[b] = 0.0f;
    }
    rays.push_back(r);
  }
  return rays;
}

TEST(KdNode, EncodesLeavesAndInteriorNodes) {
  const KdNode leaf = KdNode::leaf(123, 45);
  EXPECT_TRUE(leaf.is_leaf());
  EXPECT_EQ(leaf.first(), 123u);
  EXPECT_EQ(leaf.count(), 45u);
  KdNode inner = KdNode::interior(2, -1.25f, 77);
  EXPECT_FALSE(inner.is_leaf());
  EXPECT_EQ(inner.axis(), 2);
  EXPECT_EQ(inner.split(), -1.25f);
  EXPECT_EQ(inner.above(), 77u);
  inner.rebase({.node = 10, .ref = 1000});
  EXPECT_EQ(inner.above(), 87u);
  EXPECT_EQ(inner.split(), -1.25f);
  KdNode moved = leaf;
  moved.rebase({.node = 10, .ref = 1000});
  EXPECT_EQ(moved.first(), 1123u);
  EXPECT_EQ(moved.count(), 45u);
}

TEST(KdNode, FlagsEmptyChildrenAndKeepsThemThroughRebase) {
  KdNode inner = KdNode::interior(1, 0.5f, (1u << 28) - 1, true, false);
  EXPECT_FALSE(inner.is_leaf());
  EXPECT_EQ(inner.axis(), 1);
  EXPECT_TRUE(inner.below_empty());
  EXPECT_FALSE(inner.above_empty());
  EXPECT_EQ(inner.above(), (1u << 28) - 1);
  KdNode other = KdNode::interior(0, 2.0f, 5, false, true);
  other.rebase({.node = 3, .ref = 100});
  EXPECT_FALSE(other.below_empty());
  EXPECT_TRUE(other.above_empty());
  EXPECT_EQ(other.above(), 8u);
}

TEST(KdNode, DropEmptyLeavesFlagsThemInTheParents) {
  // Depth-first: 0 splits x (below 1, above 4); 1 splits y (below 2: empty, above 3: leaf);
  // 4 splits z (below 5: leaf, above 6: empty).
  std::vector<KdNode> nodes{
      KdNode::interior(0, 0.0f, 4), KdNode::interior(1, 1.0f, 3), KdNode::leaf(0, 0), KdNode::leaf(0, 2),
      KdNode::interior(2, 2.0f, 6), KdNode::leaf(2, 1),           KdNode::leaf(0, 0)};
  drop_empty_leaves(nodes);
  ASSERT_EQ(nodes.size(), 5u);
  EXPECT_FALSE(nodes[0].below_empty() || nodes[0].above_empty());
  EXPECT_EQ(nodes[0].above(), 3u);
  EXPECT_TRUE(nodes[1].below_empty());
  EXPECT_FALSE(nodes[1].above_empty());
  EXPECT_EQ(nodes[1].above(), 2u);
  EXPECT_EQ(nodes[2].count(), 2u);
  EXPECT_EQ(nodes[3].axis(), 2);
  EXPECT_TRUE(nodes[3].above_empty());
  EXPECT_EQ(nodes[4].count(), 1u);
  EXPECT_EQ(nodes[4].first(), 2u);
  // An empty root stays.
  std::vector<KdNode> root{KdNode::leaf(0, 0)};
  drop_empty_leaves(root);
  EXPECT_EQ(root.size(), 1u);
}

TEST(SplitPlane, AxisPlaneCrossingsAreWidenedAndZeroDirectionsNeedNoBranch) {
  Ray ray;
  ray.org = {0.0f, 1.0f, 2.0f};
  ray.dir = {0.5f, 0.0f, -0.0f};
  const PlaneRay r(ray, 0.0f);
  const PlaneCrossing x = r.cross(0, 1.0f);  // crossing at t = 2, below side first
  EXPECT_TRUE(x.below_first);
  EXPECT_LT(x.near, 2.0f);
  EXPECT_GT(x.far, 2.0f);
  // With a positional margin, a crossing at (almost) t = 0 is widened by margin / |dir| both ways.
  const PlaneRay m(ray, 0.01f);
  const PlaneCrossing at_origin = m.cross(0, 1e-9f);
  EXPECT_LE(at_origin.near, -0.019f);
  EXPECT_GE(at_origin.far, 0.019f);
  EXPECT_FALSE(m.cross(1, 1.005f).near > 10.0f);  // parallel within the margin: both sides
  EXPECT_TRUE(m.cross(1, 0.5f).far < 0.0f);       // parallel beyond it: one side
  const PlaneCrossing above = r.cross(1, 0.5f);   // parallel, origin above: never reaches the below side
  EXPECT_TRUE(above.below_first);
  EXPECT_TRUE(above.far < 0.0f);                  // -inf: the first (below) side is skipped
  const PlaneCrossing behind = r.cross(2, 3.0f);  // -0 direction: above first; origin below the plane
  EXPECT_FALSE(behind.below_first);
  EXPECT_TRUE(behind.far < 0.0f);                   // the above side is never reached
  const PlaneCrossing in_plane = r.cross(1, 1.0f);  // origin in the plane: NaN, both sides visited
  EXPECT_FALSE(in_plane.near > 10.0f);
  EXPECT_FALSE(in_plane.far < 0.0f);
}

/// The plane step at the plane x = split of a ray with origin x = org and direction x = dir.
PlaneVisit split_at_axis_plane(float org, float dir, float split, float t0, float t1) {
  Ray ray;
  ray.org = {org, 0.0f, 0.0f};
  ray.dir = {dir, 1.0f, 1.0f};
  return split_interval(PlaneRay(ray, 0.0f).cross(0, split), t0, t1);
}

TEST(SplitPlane, ParallelRaysStayOnTheirSideAndInPlaneRaysSeeBoth) {
  const PlaneVisit below = split_at_axis_plane(0.0f, 0.0f, 1.0f, 0.0f, 10.0f);
  EXPECT_TRUE(below.below_first);
  EXPECT_TRUE(below.visit_first);
  EXPECT_FALSE(below.visit_second);
  const PlaneVisit above = split_at_axis_plane(2.0f, -0.0f, 1.0f, 0.0f, 10.0f);
  EXPECT_FALSE(above.below_first);
  EXPECT_TRUE(above.visit_first);
  EXPECT_FALSE(above.visit_second);
  const PlaneVisit in = split_at_axis_plane(1.0f, 0.0f, 1.0f, 0.0f, 10.0f);
  EXPECT_TRUE(in.visit_first && in.visit_second);
  EXPECT_EQ(in.first_t1, 10.0f);
  EXPECT_EQ(in.second_t0, 0.0f);
}

TEST(SplitPlane, CrossingRaysGetWidenedHalves) {
  // Origin below, moving up: below first, crossing at t = 2.
  const PlaneVisit up = split_at_axis_plane(0.0f, 0.5f, 1.0f, 0.0f, 10.0f);
  EXPECT_TRUE(up.below_first);
  EXPECT_TRUE(up.visit_first && up.visit_second);
  EXPECT_GT(up.first_t1, 2.0f);
  EXPECT_LT(up.second_t0, 2.0f);
  // Moving down from below: the plane is behind (t = -2); only the below side is ahead.
  const PlaneVisit down = split_at_axis_plane(0.0f, -0.5f, 1.0f, 0.0f, 10.0f);
  EXPECT_FALSE(down.below_first);
  EXPECT_FALSE(down.visit_first);
  EXPECT_TRUE(down.visit_second);
  // Interval entirely before the crossing.
  const PlaneVisit early = split_at_axis_plane(0.0f, 0.5f, 1.0f, 0.0f, 1.0f);
  EXPECT_TRUE(early.visit_first);
  EXPECT_FALSE(early.visit_second);
}

/// adversarial_mesh(k) with a random soup of `soup_size` triangles (seed) appended.
Mesh adversarial_with_soup(int k, size_t soup_size, uint32_t seed) {
  Mesh mesh = adversarial_mesh(k);
  const Mesh soup = random_soup(soup_size, seed);
  const uint32_t base = uint32_t(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), soup.vertices.begin(), soup.vertices.end());
  for (glm::uvec3 t : soup.triangles) mesh.triangles.push_back(t + glm::uvec3(base));
  return mesh;
}

TEST(KdTree, MatchesBruteOnFlatGeometryInSplitPlanes) {
  const Mesh mesh = axis_planes(4);
  std::vector<Ray> rays = in_plane_rays(4, 1500, 11);
  const std::vector<Ray> more = adversarial_rays(mesh, 1500, 12);
  rays.insert(rays.end(), more.begin(), more.end());
  for (const char* name : kKdNames) {
    EXPECT_EQ(count_differences(name, mesh, rays), 0u) << name;
    EXPECT_EQ(count_differences(name, mesh, rays, {{"max_depth", "3"}}), 0u) << name;
  }
  EXPECT_EQ(count_differences("kdtree-median", mesh, rays, {{"leaf_size", "1"}, {"axis", "cycle"}}), 0u);
  EXPECT_EQ(
      count_differences("kdtree-sah", mesh, rays, {{"intersection_cost", "20"}, {"empty_bonus", "0.9"}}), 0u);
}

TEST(KdTree, MatchesBruteOnAdversarialMeshesAndInstances) {
  Mesh mesh = adversarial_with_soup(6, 300, 5);
  mesh.vertices.push_back({std::nanf(""), 0.0f, 0.0f});  // a triangle with a NaN vertex keeps its id
  mesh.triangles.push_back({0u, 1u, uint32_t(mesh.vertices.size() - 1)});
  const std::vector<Ray> rays = adversarial_rays(mesh, 3000, 21);
  for (const char* name : kKdNames) {
    EXPECT_EQ(count_differences(name, mesh, rays), 0u) << name;
    auto inst = testing::make_instances(random_soup(200, 9), name, 6);
    EXPECT_EQ(testing::count_instance_differences(name, inst, adversarial_rays(random_soup(50, 1), 2000, 4)),
              0u)
        << name;
  }
}

TEST(KdTree, LeafCopiesOnOrOffGiveTheSameHitsAsBrute) {
  const Mesh mesh = adversarial_with_soup(5, 400, 6);
  const std::vector<Ray> rays = adversarial_rays(mesh, 2000, 22);
  // on: prepared copies in leaf order; auto: those or one prepared triangle per id (by the references per
  // triangle: both occur among these structures); off: the mesh's triangles by id.
  for (const char* name : {"kdtree-sah", "kdtree-median", "bsp", "octree", "grid"})
    for (const char* copies : {"off", "on", "auto"})
      EXPECT_EQ(count_differences(name, mesh, rays, {{"leaf_copies", copies}}), 0u) << name << " " << copies;
}

TEST(KdTree, EmptyMeshAndSingleTriangle) {
  const std::vector<Ray> rays = adversarial_rays(Mesh{}, 200, 3);
  Mesh one;
  one.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  one.triangles = {{0, 1, 2}};
  for (const char* name : kKdNames) {
    EXPECT_EQ(count_differences(name, Mesh{}, rays), 0u) << name;
    EXPECT_EQ(count_differences(name, one, adversarial_rays(one, 500, 3)), 0u) << name;
  }
}

std::unique_ptr<Accelerator> built(const std::string& name, const Mesh& mesh,
                                   std::map<std::string, std::string> params = {}) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(mesh));
  auto accel = make_accelerator(name, prims, Params(std::move(params)));
  accel->build();
  return accel;
}

TEST(KdTree, StatisticsDescribeABinaryTree) {
  const Mesh mesh = random_soup(3000, 17);
  for (const char* name : kKdNames) {
    const auto accel = built(name, mesh);
    const BuildStats& s = accel->stats();
    EXPECT_EQ(s.primitives, 3000u);
    EXPECT_EQ(s.nodes, 2 * s.leaves - 1) << name;
    EXPECT_GE(s.references, 3000u) << name;
    EXPECT_GT(s.sah_cost, 0.0) << name;
    uint64_t refs = 0, leaves = 0;
    for (auto [size, count] : s.leaf_size_histogram) {
      refs += uint64_t(size) * count;
      leaves += count;
    }
    EXPECT_EQ(refs, s.references);
    EXPECT_EQ(leaves, s.leaves);
    // Stored nodes (empty leaves are flags in their parents), ids and the prepared triangles (leaf order
    // when copied, else one per triangle).
    const uint64_t stored = s.extra.at("stored_nodes").get<uint64_t>();
    EXPECT_EQ(stored, s.nodes - s.empty_leaves) << name;
    // leaf_copies=auto: copies when there are at most 3 references per triangle.
    const bool copies = s.extra.at("leaf_copies").get<bool>();
    EXPECT_EQ(copies, s.references <= 3 * s.primitives) << name;
    EXPECT_EQ(s.bytes, stored * 8 + s.references * 4 +
                           (copies ? s.references : s.primitives) * sizeof(PreparedTriangle))
        << name;
    EXPECT_LE(s.max_depth, uint32_t(auto_depth_limit(3000)));
  }
  EXPECT_LE(built("kdtree-median", mesh, {{"max_depth", "5"}})->stats().max_depth, 5u);
}

TEST(KdTree, MedianStraddleLimitBoundsTheReferences) {
  const Mesh mesh = random_soup(3000, 31, 0.1f);
  const uint64_t tight = built("kdtree-median", mesh, {{"straddle_limit", "0.2"}})->stats().references;
  const uint64_t loose = built("kdtree-median", mesh, {{"straddle_limit", "1"}})->stats().references;
  EXPECT_LT(tight, loose);
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(mesh));
  EXPECT_THROW(make_accelerator("kdtree-median", prims, testing::make_params({{"straddle_limit", "1.5"}})),
               ParamError);
  EXPECT_THROW(make_accelerator("kdtree-sah", prims, testing::make_params({{"straddle_limit", "0.5"}})),
               ParamError);
}

TEST(KdTree, SahTreeIsCheaperThanMedianTree) {
  const Mesh mesh = random_soup(4000, 23, 0.01f);
  const double sah = built("kdtree-sah", mesh)->stats().sah_cost;
  const double median = built("kdtree-median", mesh)->stats().sah_cost;
  EXPECT_LT(sah, median);
}

TEST(KdTree, SameTreeForOneAndTwoThreads) {
  const Mesh mesh = random_soup(40000, 31, 0.02f);
  const std::vector<Ray> rays = adversarial_rays(mesh, 2000, 8);
  for (const char* name : kKdNames) {
    BuildStats one, two;
    std::vector<Hit> h1(rays.size()), h2(rays.size());
    {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
      auto a = built(name, mesh);
      one = a->stats();
      a->intersect(rays, h1);
    }
    {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
      auto a = built(name, mesh);
      two = a->stats();
      a->intersect(rays, h2);
    }
    EXPECT_EQ(one.nodes, two.nodes) << name;
    EXPECT_EQ(one.references, two.references) << name;
    EXPECT_EQ(one.sah_cost, two.sah_cost) << name;
    EXPECT_EQ(0, std::memcmp(h1.data(), h2.data(), h1.size() * sizeof(Hit))) << name;
  }
}

TEST(KdTree, SahBinnedNodesMatchBruteAndCostAboutAsMuchAsTheExactSweep) {
  // exact_max 0: every node chooses a binned plane and partitions clipped boxes (sah_bins.h).
  const Mesh planes = axis_planes(4);
  EXPECT_EQ(count_differences("kdtree-sah", planes, in_plane_rays(4, 1500, 13), {{"exact_max", "0"}}), 0u);
  const Mesh mesh = adversarial_with_soup(5, 1500, 7);
  const std::vector<Ray> rays = adversarial_rays(mesh, 2000, 24);
  for (const char* exact_max : {"0", "64"})
    EXPECT_EQ(count_differences("kdtree-sah", mesh, rays, {{"exact_max", exact_max}}), 0u) << exact_max;
  for (const char* gen : {"large", "fan", "needles", "coplanar", "far", "mixed"}) {
    const Mesh hostile = generate_mesh(gen, 1500, 2, Params());
    EXPECT_EQ(
        count_differences("kdtree-sah", hostile, adversarial_rays(hostile, 800, 5), {{"exact_max", "32"}}),
        0u)
        << gen;
  }
  // Binned top levels (from 256 triangles) cost about as much as the exact sweep's tree.
  const Mesh dense = random_soup(8000, 29, 0.01f);
  const double exact = built("kdtree-sah", dense, {{"exact_max", "100000"}})->stats().sah_cost;
  const double binned = built("kdtree-sah", dense, {{"exact_max", "256"}})->stats().sah_cost;
  EXPECT_LT(binned, 1.05 * exact);
  EXPECT_GT(binned, 0.9 * exact);
}

TEST(KdTree, RejectsUnknownAndOutOfRangeParameters) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(random_soup(10, 1)));
  EXPECT_THROW(make_accelerator("kdtree-sah", prims, testing::make_params({{"leaf_size", "4"}})), ParamError);
  EXPECT_THROW(make_accelerator("kdtree-sah", prims, testing::make_params({{"traversal_cost", "-1"}})),
               ParamError);
  EXPECT_THROW(make_accelerator("kdtree-median", prims, testing::make_params({{"axis", "diagonal"}})),
               ParamError);
  EXPECT_THROW(make_accelerator("kdtree-median", prims, testing::make_params({{"leaf_size", "0"}})),
               ParamError);
  auto ok = make_accelerator("kdtree-sah", prims, testing::make_params({{"intersection_cost", "3"}}));
  EXPECT_EQ(ok->config().at("intersection_cost"), 3.0);
  EXPECT_TRUE(ok->config().contains("traversal_cost"));
}

}  // namespace
}  // namespace ab
