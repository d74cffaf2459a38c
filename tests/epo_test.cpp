// End-point overlap (accel/common/epo.h): a hand-computed tree, and every BVH's figure against a direct
// evaluation of the definition over all nodes and triangles (no pruning), binary and 8-wide.
#include "accel/common/epo.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <set>

#include "accel/bvh/bvh.h"
#include "accel/core/registry.h"
#include "tests/structure_test_helpers.h"

namespace ab {
namespace {

using testing::random_soup;

/// A two-leaf tree over two triangles given as boxes and leaf contents.
struct TwoLeaves {
  using Node = int;  ///< 0 root, 1 and 2 the leaves
  AABB boxes[3];
  Node root() const { return 0; }
  AABB box(Node n) const { return boxes[n]; }
  bool is_leaf(Node n) const { return n > 0; }
  uint32_t count(Node n) const { return n > 0 ? 1 : 0; }
  template <class F>
  void children(Node n, F&& f) const {
    if (n == 0) f(2), f(1);
  }
};

// Triangle 0 spans x, y >= 0, x + y <= 1 (area 1/2) in leaf 1's box [0,1]^3; leaf 2's box starts at
// x, y = 1/4, so it holds the corner x, y >= 1/4 of triangle 0 (area 1/8). Triangle 1 (area 1/2) only
// touches leaf 1's box in a point. EPO = leaf cost 1 x 1/8 / total area 1.
TEST(Epo, HandComputedTwoLeafTree) {
  const Triangle tris[2] = {{{0, 0, 0.5f}, {1, 0, 0.5f}, {0, 1, 0.5f}},
                            {{1, 1, 0.5f}, {2, 1, 0.5f}, {1, 2, 0.5f}}};
  TwoLeaves tree{{{{0, 0, 0}, {2, 2, 1}}, {{0, 0, 0}, {1, 1, 1}}, {{0.25f, 0.25f, 0}, {2, 2, 1}}}};
  const auto leaf = [](int n, auto&& f) { f(uint32_t(n - 1)); };
  const auto triangle = [&](size_t id) { return tris[id]; };
  EXPECT_NEAR(end_point_overlap(tree, leaf, 2, triangle), 0.125, 1e-7);
  // Boxes that overlap nothing foreign: 0.
  tree.boxes[2] = {{1, 1, 0}, {2, 2, 1}};
  EXPECT_NEAR(end_point_overlap(tree, leaf, 2, triangle), 0.0, 1e-12);
}

/// EPO by its definition: every node, every triangle outside the node's subtree, clipped to the box.
template <class V, class LeafPrims>
double epo_by_definition(const V& v, const LeafPrims& leaf_prims, const Mesh& mesh) {
  using Node = typename V::Node;
  double sum = 0.0, total = 0.0;
  for (size_t id = 0; id < mesh.triangles.size(); ++id)
    total += polygon_area(triangle_polygon(mesh.triangle(id)));
  std::function<std::set<uint32_t>(const Node&)> visit = [&](const Node& n) {
    std::set<uint32_t> held;
    float cost = 1.0f;
    if (v.is_leaf(n)) {
      leaf_prims(n, [&](uint32_t id) { held.insert(id); });
      cost = float(v.count(n));
    } else {
      v.children(n, [&](const Node& c) { held.merge(visit(c)); });
    }
    for (size_t id = 0; id < mesh.triangles.size(); ++id) {
      if (held.count(uint32_t(id))) continue;
      ClipPolygon poly = triangle_polygon(mesh.triangle(id));
      clip_polygon_to_box(poly, v.box(n));
      if (poly.n >= 3) sum += cost * polygon_area(poly);
    }
    return held;
  };
  visit(v.root());
  return sum / total;
}

/// The definition's EPO of `accel` when it is a Bvh with Config C (binary or wide tree); -1 otherwise.
template <class C>
double definition_if(const Accelerator& accel, const Mesh& mesh) {
  const auto* b = dynamic_cast<const Bvh<TrianglePrims, C>*>(&accel);
  if (!b) return -1.0;
  if (b->wide_nodes().empty()) {
    const auto leaf = [&](uint32_t i, auto&& f) {
      for (uint32_t k = 0; k < b->nodes()[i].count; ++k) f(b->order()[b->nodes()[i].offset + k]);
    };
    return epo_by_definition(BvhTreeVisitor{b->nodes()}, leaf, mesh);
  }
  const auto leaf = [&](const Bvh8TreeVisitor::Node& n, auto&& f) {
    for (uint32_t k = 4 * n.child; k < 4 * (n.child + (n.count + 3) / 4); ++k)
      if (b->block_ids()[k] != kInvalidId) f(b->block_ids()[k]);
  };
  return epo_by_definition(Bvh8TreeVisitor{b->wide_nodes()}, leaf, mesh);
}

TEST(Epo, EveryBvhMatchesTheDefinition) {
  const Mesh mesh = random_soup(400, 5, 0.12f);
  const auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(mesh));
  for (const char* name : {"bvh-median", "bvh-sah", "bvh-sweep"}) {
    for (const char* width : {"2", "8"}) {
      SCOPED_TRACE(std::string(name) + " width=" + width);
      Params params;
      params.set("width", width);
      const std::unique_ptr<Accelerator> accel = make_accelerator(name, prims, params);
      accel->build();
      EXPECT_LT(accel->stats().epo, 0.0);  // not part of the timed build
      accel->measure_quality();
      const double epo = accel->stats().epo;
      EXPECT_GT(epo, 0.0);  // overlapping triangles of 0.12 in a unit cube: boxes hold foreign surface
      const double expected =
          std::max({definition_if<BvhMedianConfig>(*accel, mesh), definition_if<BvhSahConfig>(*accel, mesh),
                    definition_if<BvhSweepConfig>(*accel, mesh)});
      ASSERT_GE(expected, 0.0) << "not a Bvh over triangles";
      EXPECT_NEAR(epo, expected, 1e-9 * expected);
      EXPECT_TRUE(to_json(accel->stats())["epo"].is_number());
    }
  }
}

TEST(Epo, NotABvhReportsNone) {
  const auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(random_soup(100, 1)));
  const std::unique_ptr<Accelerator> grid = make_accelerator("grid", prims, Params());
  grid->build();
  grid->measure_quality();
  EXPECT_LT(grid->stats().epo, 0.0);
  EXPECT_TRUE(to_json(grid->stats())["epo"].is_null());
}

}  // namespace
}  // namespace ab
