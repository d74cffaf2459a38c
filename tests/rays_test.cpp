// Ray sets: exact counts, determinism, finite values, and what each kind promises.
#include "datasets/rays.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>

#include "accel/core/error.h"
#include "accel/core/registry.h"
#include "datasets/generators.h"

namespace ab {
namespace {

/// A mesh with brute force behind a RayTarget (the ray generator's view of geometry).
struct BruteTarget {
  std::shared_ptr<const Mesh> mesh;
  std::unique_ptr<Accelerator> accel;
  RayTarget target;

  explicit BruteTarget(Mesh m) : mesh(std::make_shared<const Mesh>(std::move(m))) {
    accel = make_accelerator("brute", std::make_shared<const TrianglePrims>(mesh), Params());
    accel->build();
    target.bounds = mesh->bounds();
    target.trace = [this](std::span<const Ray> rays, std::span<Hit> hits) { accel->intersect(rays, hits); };
    target.normal = [this](const Hit& h) {
      const Triangle t = mesh->triangle(h.prim);
      return glm::cross(t.v1 - t.v0, t.v2 - t.v0);
    };
  }
};

bool same_bytes(const std::vector<Ray>& a, const std::vector<Ray>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Ray)) == 0;
}

bool finite(const vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

class RaysTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { flake_ = new BruteTarget(generate_mesh("sphereflake", 2000, 1, Params())); }
  static void TearDownTestSuite() { delete flake_; }
  static BruteTarget* flake_;
};
BruteTarget* RaysTest::flake_ = nullptr;

TEST_F(RaysTest, EveryKindExactCountFiniteAndDeterministic) {
  for (const RayKindInfo& kind : ray_kinds()) {
    SCOPED_TRACE(kind.name);
    for (uint64_t count : {0ull, 1ull, 777ull}) {
      const std::vector<Ray> a = make_rays(kind.name, flake_->target, count, 5);
      EXPECT_EQ(a.size(), count);
      EXPECT_TRUE(same_bytes(a, make_rays(kind.name, flake_->target, count, 5)));
      for (const Ray& r : a) {
        ASSERT_TRUE(finite(r.org) && finite(r.dir) && std::isfinite(r.tmin));
        ASSERT_GT(glm::length(r.dir), 0.0f);
        ASSERT_LE(r.tmin, r.tmax);
        ASSERT_GE(r.tmin, 0.0f);
      }
    }
    EXPECT_FALSE(same_bytes(make_rays(kind.name, flake_->target, 100, 1),
                            make_rays(kind.name, flake_->target, 100, 2)));
  }
}

TEST_F(RaysTest, RequiredKindsAndUnknownKind) {
  std::vector<std::string> names;
  for (const RayKindInfo& k : ray_kinds()) names.push_back(k.name);
  EXPECT_EQ(names, (std::vector<std::string>{"primary", "incoherent", "shadow", "diffuse", "ao"}));
  EXPECT_THROW(make_rays("bogus", flake_->target, 10, 1), InputError);
}

TEST_F(RaysTest, KindProperties) {
  const AABB b = flake_->target.bounds;
  const float diag = glm::length(b.extent());
  const std::vector<Ray> primary = make_rays("primary", flake_->target, 400, 3);
  for (const Ray& r : primary) {
    EXPECT_EQ(r.org, primary[0].org);  // one pinhole
    EXPECT_EQ(r.tmin, 0.0f);
    EXPECT_EQ(r.tmax, kInf);
  }
  for (const Ray& r : make_rays("incoherent", flake_->target, 400, 3)) {
    EXPECT_TRUE(b.contains(r.org));
    EXPECT_NEAR(glm::length(r.dir), 1.0f, 1e-5f);
  }
  for (const Ray& r : make_rays("shadow", flake_->target, 400, 3)) {
    EXPECT_TRUE(std::isfinite(r.tmax));
    EXPECT_GT(r.tmin, 0.0f);
    EXPECT_GT(r.org.y + r.tmax * r.dir.y, b.hi.y);  // ends at the light above the bounds
  }
  for (const Ray& r : make_rays("ao", flake_->target, 400, 3)) {
    EXPECT_GT(r.tmin, 0.0f);
    EXPECT_NEAR(r.tmax, 0.1f * diag, 1e-3f * diag);
  }
  for (const Ray& r : make_rays("diffuse", flake_->target, 400, 3)) {
    EXPECT_GT(r.tmin, 0.0f);
    EXPECT_EQ(r.tmax, kInf);
  }
}

TEST_F(RaysTest, SecondaryRaysStartAtSurfacesAndLeaveThem) {
  // Most primary rays hit the sphereflake, so most diffuse rays start within a tiny offset of a
  // surface and do not hit that surface again at once.
  const std::vector<Ray> rays = make_rays("diffuse", flake_->target, 500, 11);
  std::vector<Hit> hits(rays.size());
  flake_->accel->intersect(rays, hits);
  const float diag = glm::length(flake_->target.bounds.extent());
  size_t self_hits = 0;
  for (const Hit& h : hits) self_hits += h.found() && h.t < 1e-5f * diag;
  EXPECT_EQ(self_hits, 0u);
}

TEST(RaysEdgeCases, EmptyMeshAndNoTrace) {
  RayTarget empty;  // empty bounds, no trace function
  for (const RayKindInfo& kind : ray_kinds()) {
    const std::vector<Ray> rays = make_rays(kind.name, empty, 50, 1);
    ASSERT_EQ(rays.size(), 50u) << kind.name;
    for (const Ray& r : rays) EXPECT_TRUE(finite(r.org) && finite(r.dir)) << kind.name;
  }
}

TEST(RaysEdgeCases, MostlyEmptySpaceStillGivesExactCounts) {
  // A single tiny triangle: nearly every primary ray misses; secondary kinds must still be exact.
  Mesh m;
  m.vertices = {{0, 0, 0}, {1e-3f, 0, 0}, {0, 1e-3f, 0}, {10, 10, 10}, {10, 10, 10}, {10, 10, 10}};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};  // the second is a point: bounds are large, area tiny
  BruteTarget t(std::move(m));
  for (const char* kind : {"shadow", "diffuse", "ao"}) {
    const std::vector<Ray> rays = make_rays(kind, t.target, 300, 2);
    ASSERT_EQ(rays.size(), 300u);
    for (const Ray& r : rays) EXPECT_TRUE(finite(r.org) && finite(r.dir)) << kind;
    EXPECT_TRUE(same_bytes(rays, make_rays(kind, t.target, 300, 2)));
  }
}

// views = 1 is the one default camera; with V views, view 0's block of rays is exactly the default
// camera's rays for that block's count (the jitter depends on the ray index alone), and every view
// looks at the box centre from its own eye.
TEST_F(RaysTest, PrimaryViewsAroundTheBounds) {
  const auto& t = flake_->target;
  EXPECT_TRUE(same_bytes(make_rays("primary", t, 1000, 4), make_rays("primary", t, 1000, 4, 1)));
  const std::vector<Ray> four = make_rays("primary", t, 1000, 4, 4);
  ASSERT_EQ(four.size(), 1000u);
  EXPECT_TRUE(same_bytes(four, make_rays("primary", t, 1000, 4, 4)));
  const std::vector<Ray> first(four.begin(), four.begin() + 250);
  EXPECT_TRUE(same_bytes(first, make_rays("primary", t, 250, 4)));
  const vec3 centre = t.bounds.center();
  std::vector<vec3> eyes;
  for (int v = 0; v < 4; ++v) {
    const Ray& r = four[size_t(v) * 250];
    for (size_t i = size_t(v) * 250; i < size_t(v + 1) * 250; ++i) ASSERT_EQ(four[i].org, r.org);
    EXPECT_GT(glm::dot(r.dir, centre - r.org), 0.0f) << "view " << v;
    EXPECT_FALSE(t.bounds.contains(r.org)) << "view " << v;
    for (const vec3& e : eyes) EXPECT_GT(glm::length(e - r.org), 0.1f * glm::length(t.bounds.extent()));
    eyes.push_back(r.org);
  }
  // More views than rays: every ray still made, from the views that get one.
  EXPECT_EQ(make_rays("primary", t, 3, 1, 8).size(), 3u);
}

TEST_F(RaysTest, ViewsOnlyForPrimaryRays) {
  EXPECT_THROW(make_rays("shadow", flake_->target, 10, 1, 2), InputError);
  EXPECT_THROW(make_rays("primary", flake_->target, 10, 1, 0), InputError);
  EXPECT_NO_THROW(make_rays("shadow", flake_->target, 10, 1, 1));
}

}  // namespace
}  // namespace ab
