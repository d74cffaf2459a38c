// Octree: child boxes, traversal against brute on geometry and rays lying in the mid-planes, the mailbox,
// depth and leaf-size limits, statistics and thread-count independence.
#include "accel/octree/octree.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "structure_test_helpers.h"

namespace ab {
namespace {

using testing::adversarial_mesh;
using testing::adversarial_rays;
using testing::count_differences;
using testing::random_soup;
using testing::uniform;

/// Quads filling the three mid-planes of the unit cube and of its octants (where the octree's cells meet),
/// plus a random soup so that cells subdivide.
Mesh mid_plane_mesh() {
  Mesh m = random_soup(400, 7, 0.03f);
  const float coords[] = {0.25f, 0.5f, 0.75f};
  for (int axis = 0; axis < 3; ++axis)
    for (float c : coords) {
      const uint32_t base = uint32_t(m.vertices.size());
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int k = 0; k < 4; ++k) {
        vec3 p(0.0f);
        p[axis] = c;
        p[u] = 0.1f + 0.8f * float(k == 1 || k == 2);
        p[v] = 0.1f + 0.8f * float(k >= 2);
        m.vertices.push_back(p);
      }
      m.triangles.push_back({base, base + 1, base + 2});
      m.triangles.push_back({base, base + 2, base + 3});
    }
  // Pin the bounds to the unit cube so the mid-planes are at 0.25, 0.5, 0.75.
  const uint32_t base = uint32_t(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {{0, 0, 0}, {1, 1, 1}, {0, 0, 0}});
  m.triangles.push_back({base, base + 1, base + 2});
  return m;
}

/// Rays lying in the mid-planes (zero direction component there) and along their intersection lines.
std::vector<Ray> mid_plane_rays(size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  const float coords[] = {0.25f, 0.5f, 0.75f};
  std::vector<Ray> rays;
  for (size_t n = 0; n < count; ++n) {
    Ray r;
    const int a = int(n % 3), b = (a + 1) % 3;
    r.org = {uniform(rng, -0.2f, 1.2f), uniform(rng, -0.2f, 1.2f), uniform(rng, -0.2f, 1.2f)};
    r.dir = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
    r.org[a] = coords[rng() % 3];
    r.dir[a] = 0.0f;
    if (n % 2) {
      r.org[b] = coords[rng() % 3];
      r.dir[b] = -0.0f;
    }
    rays.push_back(r);
  }
  return rays;
}

std::unique_ptr<Accelerator> built(const Mesh& mesh, std::map<std::string, std::string> params = {}) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(mesh));
  auto accel = make_accelerator("octree", prims, Params(std::move(params)));
  accel->build();
  return accel;
}

TEST(Octree, OctantBoxesSplitAtTheMidpoint) {
  const AABB b{{0, -2, 4}, {2, 2, 5}};
  for (int c = 0; c < 8; ++c) {
    const AABB o = octant_box(b, c);
    EXPECT_EQ(o.lo.x, (c & 1) ? 1.0f : 0.0f);
    EXPECT_EQ(o.hi.y, (c & 2) ? 2.0f : 0.0f);
    EXPECT_EQ(o.lo.z, (c & 4) ? 4.5f : 4.0f);
    EXPECT_EQ(o.extent(), 0.5f * b.extent());
  }
}

TEST(Octree, MatchesBruteOnGeometryAndRaysInMidPlanes) {
  const Mesh mesh = mid_plane_mesh();
  std::vector<Ray> rays = mid_plane_rays(2000, 3);
  const std::vector<Ray> more = adversarial_rays(mesh, 1500, 4);
  rays.insert(rays.end(), more.begin(), more.end());
  EXPECT_EQ(count_differences("octree", mesh, rays), 0u);
  EXPECT_EQ(count_differences("octree", mesh, rays, {{"leaf_size", "1"}, {"max_depth", "6"}}), 0u);
  EXPECT_EQ(count_differences("octree", mesh, rays, {{"max_depth", "0"}}), 0u);
  EXPECT_EQ(count_differences("octree", mesh, rays, {{"max_depth", "1"}}), 0u);
}

TEST(Octree, MatchesBruteOnAdversarialMeshesAndInstances) {
  const Mesh mesh = adversarial_mesh(7);
  EXPECT_EQ(count_differences("octree", mesh, adversarial_rays(mesh, 3000, 5), {{"leaf_size", "2"}}), 0u);
  auto inst = testing::make_instances(random_soup(200, 2), "octree", 7);
  EXPECT_EQ(
      testing::count_instance_differences("octree", inst, adversarial_rays(random_soup(50, 1), 2000, 6)), 0u);
}

TEST(Octree, MailboxTestsATriangleOncePerRay) {
  // Triangles larger than the leaves: a ray meets each in several leaves and tests it once.
  const Mesh mesh = random_soup(3000, 23, 0.05f);
  const std::vector<Ray> rays = adversarial_rays(mesh, 1000, 24);
  for (const char* copies : {"off", "on"}) {
    auto accel = built(mesh, {{"leaf_copies", copies}});
    std::vector<Hit> hits(rays.size());
    RayCounters c;
    accel->intersect_counted(rays, hits, c);
    EXPECT_GT(c.mailbox_skips, 0u) << copies;
    EXPECT_EQ(count_differences("octree", mesh, rays, {{"leaf_copies", copies}}), 0u) << copies;
  }
}

TEST(Octree, RespectsDepthAndLeafSize) {
  const Mesh mesh = random_soup(5000, 9, 0.01f);
  for (int depth : {0, 2, 5}) {
    const auto accel =
        built(mesh, {{"max_depth", std::to_string(depth)}, {"leaf_size", "4"}, {"auto_depth", "off"}});
    const BuildStats& s = accel->stats();
    EXPECT_LE(s.max_depth, uint32_t(depth));
    EXPECT_EQ((s.nodes - 1) % 8, 0u);  // every interior node has eight children
    EXPECT_EQ(s.leaves, s.nodes - (s.nodes - 1) / 8);
    EXPECT_GE(s.references, 5000u);
  }
  const auto deep = built(mesh, {{"max_depth", "12"}, {"leaf_size", "8"}});
  EXPECT_GT(deep->stats().max_depth, 3u);
  // Small triangles: almost every leaf at the limit holds at most leaf_size triangles.
  uint64_t big = 0;
  for (auto [size, count] : deep->stats().leaf_size_histogram)
    if (size > 8) big += count;
  EXPECT_LT(big, deep->stats().leaves / 20 + 1);
}

TEST(Octree, SameTreeForOneAndTwoThreads) {
  const Mesh mesh = random_soup(30000, 13, 0.02f);
  const std::vector<Ray> rays = adversarial_rays(mesh, 2000, 8);
  BuildStats one, two;
  std::vector<Hit> h1(rays.size()), h2(rays.size());
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    auto a = built(mesh);
    one = a->stats();
    a->intersect(rays, h1);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    auto a = built(mesh);
    two = a->stats();
    a->intersect(rays, h2);
  }
  EXPECT_EQ(one.nodes, two.nodes);
  EXPECT_EQ(one.references, two.references);
  EXPECT_EQ(one.sah_cost, two.sah_cost);
  EXPECT_EQ(0, std::memcmp(h1.data(), h2.data(), h1.size() * sizeof(Hit)));
}

TEST(Octree, RejectsBadParameters) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(random_soup(10, 1)));
  EXPECT_THROW(make_accelerator("octree", prims, testing::make_params({{"max_depth", "99"}})), ParamError);
  EXPECT_THROW(make_accelerator("octree", prims, testing::make_params({{"bins", "4"}})), ParamError);
}

}  // namespace
}  // namespace ab
