// Tests of bvh-sbvh (spatial splits, accel/bvh/sbvh.cpp): hits identical to brute force with spatial splits
// forced everywhere, the reference budget on the hostile generators, every point of a triangle inside the box
// of a leaf holding one of its references, the SAH cost against bvh-sah's, and the same tree for any
// number of threads. (The conformance tests cover its defaults through its registration.)
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "accel/bvh/sbvh.h"
#include "accel/core/clip.h"
#include "accel/core/registry.h"
#include "datasets/generators.h"
#include "tests/structure_test_helpers.h"

namespace ab {
namespace {

using testing::adversarial_mesh;
using testing::adversarial_rays;
using testing::built_accelerator;

using testing::count_differences;
using testing::random_soup;

/// Spatial splits tried at every node (alpha 0) with room for two references per triangle.
const std::map<std::string, std::string> kForced = {{"alpha", "0"}, {"ref_budget", "2"}};

/// The builder itself over the mesh's triangles.
BvhBuildResult build_sbvh(const Mesh& mesh, const BvhSbvhConfig& config) {
  std::vector<AABB> bounds(mesh.size());
  for (size_t i = 0; i < mesh.size(); ++i) bounds[i] = mesh.triangle(i).bounds();
  return build_bvh(config, bounds, [&](uint32_t i, const AABB& box) {
    return clipped_triangle_bounds(mesh.triangle(i), box);
  });
}

TEST(Sbvh, EqualsBruteWithSpatialSplitsForced) {
  const std::vector<Mesh> meshes = {
      adversarial_mesh(12), random_soup(3000, 7, 0.25f), generate_mesh("fan", 2000, 1, Params()),
      generate_mesh("large", 2000, 2, Params()), generate_mesh("needles", 2000, 3, Params())};
  for (size_t m = 0; m < meshes.size(); ++m) {
    const std::vector<Ray> rays = adversarial_rays(meshes[m], 3000, uint32_t(11 + m));
    for (const char* width : {"2", "8"}) {
      auto params = kForced;
      params["width"] = width;
      EXPECT_EQ(count_differences("bvh-sbvh", meshes[m], rays, params), 0u)
          << "mesh " << m << " width " << width;
    }
    EXPECT_EQ(count_differences("bvh-sbvh", meshes[m], rays), 0u) << "mesh " << m << " defaults";
  }
}

TEST(Sbvh, InstancesEqualBrute) {
  const Mesh mesh = random_soup(800, 9, 0.2f);
  const auto instances = testing::make_instances(mesh, "bvh-sbvh", 7);
  Mesh bounds_mesh = mesh;
  bounds_mesh.vertices.push_back({2.0f, 1.0f, 1.0f});  // the rays cover the translated copies
  EXPECT_EQ(
      testing::count_instance_differences("bvh-sbvh", instances, adversarial_rays(bounds_mesh, 2000, 5)), 0u);
}

TEST(Sbvh, ReferencesStayWithinTheBudget) {
  for (const char* gen : {"large", "fan", "needles", "slivers", "coplanar", "mixed"}) {
    const Mesh mesh = generate_mesh(gen, 5000, 1, Params());
    for (const char* budget : {"1", "1.2", "2"}) {
      const BuildStats s = built_accelerator("bvh-sbvh", mesh, {{"ref_budget", budget}})->stats();
      EXPECT_GE(s.references, s.primitives) << gen << " " << budget;
      EXPECT_LE(double(s.references), std::stod(budget) * double(s.primitives)) << gen << " " << budget;
      EXPECT_LT(s.build_seconds, 20.0) << gen << " " << budget;
    }
  }
  // The budget is used where spatial splits pay: large overlapping triangles.
  const BuildStats s = built_accelerator("bvh-sbvh", generate_mesh("large", 5000, 1, Params()))->stats();
  EXPECT_GT(s.references, s.primitives);
}

/// True when p lies in box grown by tolerance on every side.
bool near_box(const AABB& box, const vec3& p, float tolerance) {
  return box.contains(p) || AABB{box.lo - vec3(tolerance), box.hi + vec3(tolerance)}.contains(p);
}

TEST(Sbvh, EveryPointOfATriangleLiesInALeafBoxOfOneOfItsReferences) {
  const Mesh mesh = random_soup(1500, 5, 0.3f);
  BvhSbvhConfig config;
  config.alpha = 0.0;
  config.ref_budget = 2.0;
  const BvhBuildResult r = build_sbvh(mesh, config);
  ASSERT_GT(r.order.size(), mesh.size());  // spatial splits were made
  std::vector<std::vector<AABB>> leaf_boxes(mesh.size());
  for (size_t i = 0; i < r.nodes.size(); ++i)
    if (i != 1 && r.nodes[i].is_leaf())
      for (uint32_t k = r.nodes[i].offset; k < r.nodes[i].offset + r.nodes[i].count; ++k)
        leaf_boxes[r.order[k]].push_back(r.nodes[i].box());
  const float tolerance = 0x1p-20f;  // rounding of the sample points (coordinates within 2)
  for (size_t t = 0; t < mesh.size(); ++t) {
    const Triangle tri = mesh.triangle(t);
    ASSERT_FALSE(leaf_boxes[t].empty()) << t;
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; i + j <= 8; ++j) {
        const float u = float(i) / 8.0f, v = float(j) / 8.0f;
        const vec3 p = tri.v0 + u * (tri.v1 - tri.v0) + v * (tri.v2 - tri.v0);
        bool inside = false;
        for (const AABB& box : leaf_boxes[t]) inside = inside || near_box(box, p, tolerance);
        EXPECT_TRUE(inside) << "triangle " << t << " sample " << i << "," << j;
      }
  }
}

// The binary trees, whose builders minimize the reported cost (costs 1 and 1); for width 8 both price a leaf
// by its blocks of four triangles, which the reported figure does not.
TEST(Sbvh, SahCostNoWorseThanBinnedSah) {
  for (const char* gen : {"sphereflake", "terrain", "soup"}) {
    const Mesh mesh = generate_mesh(gen, 20000, 1, Params());
    const double sah = built_accelerator("bvh-sah", mesh, {{"width", "2"}})->stats().sah_cost;
    const double sbvh = built_accelerator("bvh-sbvh", mesh, {{"width", "2"}})->stats().sah_cost;
    EXPECT_LE(sbvh, sah) << gen;
  }
}

TEST(Sbvh, SameTreeForAnyThreadCountWithParallelPathsForced) {
  const Mesh mesh = random_soup(34000, 3, 0.05f);  // above the parallel reductions' threshold
  BvhSbvhConfig config;
  config.parallel_threshold = 64;
  BvhBuildResult one, two;
  tbb::task_arena(1).execute([&] { one = build_sbvh(mesh, config); });
  tbb::task_arena(2).execute([&] { two = build_sbvh(mesh, config); });
  ASSERT_EQ(one.nodes.size(), two.nodes.size());
  EXPECT_EQ(std::memcmp(one.nodes.data(), two.nodes.data(), one.nodes.size() * sizeof(BvhNode)), 0);
  EXPECT_EQ(one.order, two.order);
  EXPECT_GT(one.order.size(), mesh.size());
}

}  // namespace
}  // namespace ab
