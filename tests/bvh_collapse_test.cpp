// Tests of the SAH-optimal 8-wide collapse (collapse.h, Ylitie, Karras and Laine 2017): its cost by the
// dynamic programming's own measure (the summed area of the wide nodes, the leaves being the same) is never
// above the greedy collapse's, every binary leaf becomes exactly one lane, and the hits stay identical.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "accel/bvh/build.h"
#include "accel/bvh/collapse.h"
#include "datasets/generators.h"
#include "tests/structure_test_helpers.h"

namespace ab {
namespace {

/// The DP's measure of a wide tree: the summed surface area of its nodes (each the union of its lanes).
double summed_node_area(const Bvh8NodeArray& wide) {
  double sum = 0.0;
  for (const Bvh8Node& node : wide) {
    AABB box;
    for (int k = 0; k < Bvh8Node::kWidth; ++k)
      if (node.used(k)) box.extend(node.box(k));
    sum += box.area();
  }
  return sum;
}

/// The leaf lanes of a wide tree as (first, count) pairs, sorted.
std::vector<std::pair<uint32_t, uint32_t>> leaf_lanes(const Bvh8NodeArray& wide) {
  std::vector<std::pair<uint32_t, uint32_t>> lanes;
  for (const Bvh8Node& node : wide)
    for (int k = 0; k < Bvh8Node::kWidth; ++k)
      if (node.used(k) && node.count[k] > 0) lanes.push_back({node.child[k], node.count[k]});
  std::sort(lanes.begin(), lanes.end());
  return lanes;
}

BvhBuildResult binary_sah_tree(const Mesh& mesh) {
  std::vector<AABB> bounds(mesh.size());
  std::vector<vec3> centroids(mesh.size());
  for (size_t i = 0; i < mesh.size(); ++i)
    bounds[i] = mesh.triangle(i).bounds(), centroids[i] = bounds[i].center();
  BvhSahConfig config;
  config.costs.block = 4;  // as bvh-sah builds it for width 8
  return build_bvh(config, bounds, centroids);
}

TEST(BvhCollapse, OptimalNeverCostsMoreThanGreedyAndKeepsEveryLeaf) {
  for (const char* gen : {"sphereflake", "terrain", "soup", "large"}) {
    const BvhBuildResult tree = binary_sah_tree(generate_mesh(gen, 20000, 1, Params()));
    const Bvh8NodeArray greedy = collapse_to_bvh8(tree.nodes, BvhCollapse::greedy);
    const Bvh8NodeArray optimal = collapse_to_bvh8(tree.nodes, BvhCollapse::optimal);
    EXPECT_LE(summed_node_area(optimal), summed_node_area(greedy) * (1.0 + 1e-6)) << gen;
    std::vector<std::pair<uint32_t, uint32_t>> binary_leaves;
    for (size_t i = 0; i < tree.nodes.size(); ++i)
      if (i != 1 && tree.nodes[i].is_leaf())
        binary_leaves.push_back({tree.nodes[i].offset, tree.nodes[i].count});
    std::sort(binary_leaves.begin(), binary_leaves.end());
    EXPECT_EQ(leaf_lanes(optimal), binary_leaves) << gen;
    EXPECT_EQ(leaf_lanes(greedy), binary_leaves) << gen;
  }
}

TEST(BvhCollapse, OneLeafTreeIsTheRootsOnlyLane) {
  const BvhBuildResult tree = binary_sah_tree(testing::random_soup(3, 1));
  const Bvh8NodeArray optimal = collapse_to_bvh8(tree.nodes, BvhCollapse::optimal);
  ASSERT_EQ(optimal.size(), 1u);
  EXPECT_EQ(optimal[0].count[0], tree.nodes[0].count);
}

TEST(BvhCollapse, OptimalEqualsBrute) {
  const std::vector<Mesh> meshes = {testing::adversarial_mesh(12), testing::random_soup(3000, 4, 0.1f),
                                    generate_mesh("sphereflake", 5000, 1, Params())};
  for (size_t m = 0; m < meshes.size(); ++m) {
    const std::vector<Ray> rays = testing::adversarial_rays(meshes[m], 2000, uint32_t(3 + m));
    for (const char* name : {"bvh-sah", "bvh-sbvh"})
      EXPECT_EQ(testing::count_differences(name, meshes[m], rays, {{"collapse", "optimal"}}), 0u)
          << name << " mesh " << m;
  }
}

}  // namespace
}  // namespace ab
