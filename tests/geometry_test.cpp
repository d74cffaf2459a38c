#include <gtest/gtest.h>

#include <bit>

#include "accel/core/box_test.h"
#include "accel/core/triangle.h"
#include "structure_test_helpers.h"

namespace ab {
namespace {

const Triangle kUnit{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

Ray ray_down(float x, float y) {
  Ray r;
  r.org = {x, y, 1};
  r.dir = {0, 0, -1};
  return r;
}

TEST(TriangleKernel, InteriorHitHasExpectedTAndBarycentrics) {
  TriangleHit h;
  ASSERT_TRUE(intersect_triangle(ray_down(0.25f, 0.5f), kUnit, h));
  EXPECT_FLOAT_EQ(h.t, 1.0f);
  EXPECT_FLOAT_EQ(h.u, 0.25f);  // weight of v1 = (1,0,0)
  EXPECT_FLOAT_EQ(h.v, 0.5f);   // weight of v2 = (0,1,0)
}

TEST(TriangleKernel, UnnormalizedDirectionScalesT) {
  Ray r = ray_down(0.25f, 0.25f);
  r.dir = {0, 0, -4};
  TriangleHit h;
  ASSERT_TRUE(intersect_triangle(r, kUnit, h));
  EXPECT_FLOAT_EQ(h.t, 0.25f);
}

TEST(TriangleKernel, EdgesAndVerticesCount) {
  TriangleHit h;
  EXPECT_TRUE(intersect_triangle(ray_down(0.5f, 0.0f), kUnit, h));  // edge v0-v1
  EXPECT_TRUE(intersect_triangle(ray_down(0.0f, 0.5f), kUnit, h));  // edge v0-v2
  EXPECT_TRUE(intersect_triangle(ray_down(0.5f, 0.5f), kUnit, h));  // edge v1-v2
  EXPECT_TRUE(intersect_triangle(ray_down(0.0f, 0.0f), kUnit, h));  // vertex v0
  EXPECT_TRUE(intersect_triangle(ray_down(1.0f, 0.0f), kUnit, h));  // vertex v1
  EXPECT_FALSE(intersect_triangle(ray_down(0.6f, 0.6f), kUnit, h));
  EXPECT_FALSE(intersect_triangle(ray_down(-0.01f, 0.5f), kUnit, h));
}

TEST(TriangleKernel, ParallelAndBehindMiss) {
  TriangleHit h;
  Ray parallel;
  parallel.org = {-1, 0.25f, 0};
  parallel.dir = {1, 0, 0};  // in the triangle's plane
  EXPECT_FALSE(intersect_triangle(parallel, kUnit, h));
  Ray behind = ray_down(0.25f, 0.25f);
  behind.dir = {0, 0, 1};  // the triangle is at t = -1
  EXPECT_FALSE(intersect_triangle(behind, kUnit, h));
}

TEST(TriangleKernel, TminTmaxAreInclusive) {
  TriangleHit h;
  Ray r = ray_down(0.25f, 0.25f);
  r.tmax = 1.0f;
  EXPECT_TRUE(intersect_triangle(r, kUnit, h));
  r.tmax = 0.999f;
  EXPECT_FALSE(intersect_triangle(r, kUnit, h));
  r.tmax = kInf;
  r.tmin = 1.0f;
  EXPECT_TRUE(intersect_triangle(r, kUnit, h));
  r.tmin = 1.001f;
  EXPECT_FALSE(intersect_triangle(r, kUnit, h));
}

TEST(TriangleKernel, DegenerateTrianglesNeverHit) {
  TriangleHit h;
  const Triangle point{{0.25f, 0.25f, 0}, {0.25f, 0.25f, 0}, {0.25f, 0.25f, 0}};
  const Triangle repeated{{0, 0, 0}, {1, 1, 0}, {1, 1, 0}};
  const Triangle collinear{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  for (const Triangle& t : {point, repeated, collinear}) {
    for (float x : {0.0f, 0.25f, 0.5f, 1.0f}) {
      Ray r = ray_down(x, x);
      r.dir = {0.1f, 0.2f, -1.0f};
      EXPECT_FALSE(intersect_triangle(r, t, h));
      EXPECT_FALSE(intersect_triangle(ray_down(x, 0.0f), t, h));
    }
  }
}

TEST(TriangleKernel, RaysLyingInAnObliquePlaneNeverHit) {
  // An oblique triangle: its plane is not an axis plane, so den is rounding noise, not exactly 0.
  const Triangle tri{{0.1f, 0.2f, 0.3f}, {1.7f, 0.9f, -0.4f}, {0.3f, 1.9f, 1.1f}};
  const vec3 e1 = tri.v1 - tri.v0, e2 = tri.v2 - tri.v0;
  TriangleHit h;
  int tested = 0;
  for (float a = -1.0f; a <= 1.0f; a += 0.125f)
    for (float b = -1.0f; b <= 1.0f; b += 0.25f) {
      const Ray r{tri.v0 - e1 + a * e2, e1 + b * e2, 0.0f, kInf};  // origin and direction in the plane
      EXPECT_FALSE(intersect_triangle(r, tri, h)) << a << " " << b << ": t=" << h.t;
      ++tested;
    }
  EXPECT_GT(tested, 100);
  // A steep ray through the same triangle still hits.
  const vec3 n = glm::cross(e1, e2);
  EXPECT_TRUE(intersect_triangle({tri.centroid() + n, -n, 0.0f, kInf}, tri, h));
  EXPECT_NEAR(h.t, 1.0f, 1e-5f);
}

TEST(TriangleKernel, PreparedTrianglesGiveTheKernelsBits) {
  // Degenerate, sliver and ordinary triangles, rays through their vertices and edges and in their planes.
  using testing::adversarial_rays;
  const Mesh mesh = testing::adversarial_mesh(6), soup = testing::random_soup(400, 5, 0.5f);
  std::vector<Ray> rays = adversarial_rays(mesh, 1500, 9);
  const auto more = adversarial_rays(soup, 1500, 10);
  rays.insert(rays.end(), more.begin(), more.end());
  size_t hits = 0, tests = 0;
  for (const Mesh* m : {&mesh, &soup})
    for (size_t i = 0; i < m->size(); ++i) {
      const Triangle tri = m->triangle(i);
      const PreparedTriangle prepared = prepare_triangle(tri, uint32_t(i));
      ASSERT_EQ(prepared.id, uint32_t(i));
      for (size_t r = i % 5; r < rays.size(); r += 7, ++tests) {
        const float l1_dir = l1_norm(to_lanes(rays[r].dir));
        TriangleHit a{}, b{};
        const bool scalar = intersect_triangle(rays[r], tri, a);
        ASSERT_EQ(intersect_prepared(rays[r], l1_dir, prepared, b), scalar)
            << "triangle " << i << " ray " << r;
        if (!scalar) continue;
        ++hits;
        EXPECT_EQ(std::bit_cast<uint32_t>(a.t), std::bit_cast<uint32_t>(b.t));
        EXPECT_EQ(std::bit_cast<uint32_t>(a.u), std::bit_cast<uint32_t>(b.u));
        EXPECT_EQ(std::bit_cast<uint32_t>(a.v), std::bit_cast<uint32_t>(b.v));
      }
    }
  EXPECT_GT(hits, 1000u) << tests;  // the comparison saw real hits
}

TEST(AcceptanceRule, CloserThenLowerInstanceThenLowerPrim) {
  Hit best{1.0f, 5, 2, 0, 0};
  EXPECT_TRUE(is_better_hit(0.5f, 9, 9, best));
  EXPECT_FALSE(is_better_hit(1.5f, 0, 0, best));
  EXPECT_TRUE(is_better_hit(1.0f, 1, 9, best));
  EXPECT_FALSE(is_better_hit(1.0f, 3, 0, best));
  EXPECT_TRUE(is_better_hit(1.0f, 2, 4, best));
  EXPECT_FALSE(is_better_hit(1.0f, 2, 5, best));
}

bool hits_box(const Ray& ray, const AABB& box, float& t0, float& t1) {
  t0 = ray.tmin;
  t1 = ray.tmax;
  return slab_test(box, RayBoxData(ray), t0, t1);
}

TEST(SlabTest, ZeroDirectionComponentsGiveNoNaN) {
  const AABB box{{0, 0, 0}, {1, 1, 1}};
  float t0, t1;
  Ray r;
  r.org = {0.5f, 0.5f, -1};
  r.dir = {0, 0, 1};
  ASSERT_TRUE(hits_box(r, box, t0, t1));
  EXPECT_NEAR(t0, 1.0f, 1e-4f);
  EXPECT_NEAR(t1, 2.0f, 1e-4f);
  // Origin exactly on the x = 0 slab plane while parallel to it: 0 * inf must not poison the interval.
  r.org = {0.0f, 0.5f, -1};
  ASSERT_TRUE(hits_box(r, box, t0, t1));
  EXPECT_FALSE(std::isnan(t0) || std::isnan(t1));
  r.org = {1.0f, 1.0f, -1};
  r.dir = {-0.0f, -0.0f, 1};
  ASSERT_TRUE(hits_box(r, box, t0, t1));
  EXPECT_NEAR(t1, 2.0f, 1e-4f);
  // Parallel and outside the slab: miss, for +0 and -0.
  r.org = {1.5f, 0.5f, -1};
  r.dir = {0, 0, 1};
  EXPECT_FALSE(hits_box(r, box, t0, t1));
  r.dir = {-0.0f, 0, 1};
  EXPECT_FALSE(hits_box(r, box, t0, t1));
}

TEST(SlabTest, NegativeComponentsAndLimits) {
  const AABB box{{0, 0, 0}, {1, 1, 1}};
  float t0, t1;
  Ray r;
  r.org = {2, 2, 2};
  r.dir = {-1, -1, -1};
  ASSERT_TRUE(hits_box(r, box, t0, t1));
  EXPECT_NEAR(t0, 1.0f, 1e-4f);
  EXPECT_NEAR(t1, 2.0f, 1e-4f);
  r.tmax = 0.5f;  // ends before the box
  EXPECT_FALSE(hits_box(r, box, t0, t1));
  r.tmax = kInf;
  r.dir = {1, 1, 1};  // box behind the origin
  EXPECT_FALSE(hits_box(r, box, t0, t1));
  // Far distance is widened (Ize 2013), never narrowed.
  r.org = {0.5f, 0.5f, -1};
  r.dir = {0, 0, 1};
  ASSERT_TRUE(hits_box(r, box, t0, t1));
  EXPECT_GE(t1, 2.0f);
  EXPECT_LE(t0, 1.0f);
}

}  // namespace
}  // namespace ab
