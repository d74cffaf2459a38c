// Tests of the BVH builders themselves (build_bvh): the presorted full sweep against a naive sweep that
// re-sorts at every node, thread independence with the parallel paths forced on, forced splits.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>

#include "accel/bvh/build.h"
#include "accel/bvh/collapse.h"
#include "accel/bvh/sah_split.h"
#include "accel/bvh/tree_visitors.h"
#include "accel/common/tree_stats.h"
#include "tests/structure_test_helpers.h"

namespace ab {
namespace {

using testing::random_soup;

struct Inputs {
  std::vector<AABB> bounds;
  std::vector<vec3> centroids;
};

/// The figures of a built tree, from the one statistics walk.
BuildStats stats_of(const BvhBuildResult& r) {
  BuildStats stats;
  if (!r.nodes.empty()) walk_tree_stats(BvhTreeVisitor{r.nodes}, stats);
  return stats;
}

Inputs inputs_of(const Mesh& mesh) {
  Inputs in;
  for (size_t i = 0; i < mesh.size(); ++i) {
    in.bounds.push_back(mesh.triangle(i).bounds());
    in.centroids.push_back(in.bounds.back().center());
  }
  return in;
}

/// The textbook full sweep: sort the node's primitives on each axis (centroid, then id), evaluate every
/// split, recurse. Checks the built tree node by node: the same box, the same leaves with the same ids.
class NaiveSweepCheck {
 public:
  NaiveSweepCheck(const Inputs& in, const BvhSweepConfig& config, const BvhBuildResult& built)
      : in_(in), config_(config), built_(built) {}

  void check(std::vector<uint32_t> ids, uint32_t node, int depth) {
    AABB box;
    for (uint32_t id : ids) box.extend(in_.bounds[id]);
    const BvhNode& n = built_.nodes[node];
    const AABB built_box = n.box();
    ASSERT_EQ(std::memcmp(&built_box, &box, sizeof(AABB)), 0) << "node " << node;
    const uint32_t count = uint32_t(ids.size());
    SahSplit best;
    std::vector<uint32_t> best_order;
    uint32_t decision = 0;
    if (depth < config_.max_depth && count > 1) {
      for (int a = 0; a < 3; ++a) sweep_axis(ids, a, box.area(), best, best_order);
      decision = sah_decision(count, best, config_);
    }
    if (decision == 0) {
      ASSERT_TRUE(n.is_leaf()) << "node " << node;
      std::vector<uint32_t> leaf(built_.order.begin() + n.offset, built_.order.begin() + n.offset + n.count);
      std::sort(leaf.begin(), leaf.end());
      std::sort(ids.begin(), ids.end());
      EXPECT_EQ(leaf, ids);
      return;
    }
    ASSERT_FALSE(n.is_leaf()) << "node " << node;
    if (decision != count) {  // forced split: halves in x order
      best_order = sorted(ids, 0);
      best.position = int(decision);
    }
    const auto mid = best_order.begin() + best.position;
    check(std::vector<uint32_t>(best_order.begin(), mid), n.offset, depth + 1);
    check(std::vector<uint32_t>(mid, best_order.end()), n.offset + 1, depth + 1);
  }

 private:
  std::vector<uint32_t> sorted(std::vector<uint32_t> ids, int a) const {
    std::sort(ids.begin(), ids.end(), [&](uint32_t x, uint32_t y) {
      const float cx = in_.centroids[x][a], cy = in_.centroids[y][a];
      return cx != cy ? cx < cy : x < y;
    });
    return ids;
  }
  void sweep_axis(const std::vector<uint32_t>& ids, int a, float area, SahSplit& best,
                  std::vector<uint32_t>& order) {
    const std::vector<uint32_t> s = sorted(ids, a);
    if (!(in_.centroids[s.back()][a] > in_.centroids[s.front()][a])) return;
    const size_t n = s.size();
    for (size_t i = 1; i < n; ++i) {
      AABB left, right;
      for (size_t k = 0; k < i; ++k) left.extend(in_.bounds[s[k]]);
      for (size_t k = i; k < n; ++k) right.extend(in_.bounds[s[k]]);
      const float c = config_.costs.split(area, left.area(), i, right.area(), n - i);
      if (c < best.cost) best = {a, int(i), c}, order = s;
    }
  }

  const Inputs& in_;
  const BvhSweepConfig& config_;
  const BvhBuildResult& built_;
};

TEST(BvhBuild, PresortedSweepEqualsResortingAtEveryNode) {
  Mesh mesh = random_soup(600, 3, 0.2f);
  // Equal centroids on some axes (ties resolved by id) and a cluster of duplicates (forced splits).
  for (size_t i = 0; i < 40; ++i) mesh.triangles.push_back(mesh.triangles[i % 4]);
  const Inputs in = inputs_of(mesh);
  BvhSweepConfig config;
  config.max_leaf_size = 4;
  config.parallel_threshold = 64;
  const BvhBuildResult built = build_bvh(config, in.bounds, in.centroids);
  std::vector<uint32_t> all(mesh.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  NaiveSweepCheck(in, config, built).check(all, 0, 0);
}

/// Builds with `threads` threads and the parallel paths forced on for small subtrees.
template <class Config>
BvhBuildResult build_with(const Inputs& in, int threads) {
  Config config;
  config.parallel_threshold = 32;
  tbb::task_arena arena(threads);
  BvhBuildResult r;
  arena.execute([&] { r = build_bvh(config, in.bounds, in.centroids); });
  return r;
}

/// The same tree with one and with two threads, for the builder of Config.
template <class Config>
void expect_same_tree_for_any_thread_count(const Inputs& in, const char* name) {
  const BvhBuildResult one = build_with<Config>(in, 1), two = build_with<Config>(in, 2);
  ASSERT_EQ(one.nodes.size(), two.nodes.size()) << name;
  EXPECT_EQ(std::memcmp(one.nodes.data(), two.nodes.data(), one.nodes.size() * sizeof(BvhNode)), 0) << name;
  EXPECT_EQ(one.order, two.order) << name;
  EXPECT_EQ(stats_of(one).sah_cost, stats_of(two).sah_cost);
}

TEST(BvhBuild, SameTreeForAnyThreadCountWithParallelPathsForced) {
  const Inputs in = inputs_of(random_soup(70000, 21, 0.01f));  // above the parallel binning threshold
  expect_same_tree_for_any_thread_count<BvhSahConfig>(in, "bvh-sah");
  expect_same_tree_for_any_thread_count<BvhSweepConfig>(in, "bvh-sweep");
  expect_same_tree_for_any_thread_count<BvhMedianConfig>(in, "bvh-median");
}

/// The flattened layout (slots.h): root at 0, padding at 1, and the children of the k-th interior node of a
/// depth-first walk (left child first) at pair 2 + 2k, with nothing after the last pair.
void expect_depth_first_pairs(const BvhBuildResult& r, const char* name) {
  ASSERT_GE(r.nodes.size(), 2u) << name;
  EXPECT_EQ(r.nodes[1].count, 1u) << name;  // the padding node
  uint32_t next_pair = 2;
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const BvhNode& n = r.nodes[stack.back()];
    stack.pop_back();
    if (n.is_leaf()) continue;
    ASSERT_EQ(n.offset, next_pair) << name;
    next_pair += 2;
    stack.push_back(n.offset + 1);
    stack.push_back(n.offset);
  }
  EXPECT_EQ(r.nodes.size(), next_pair) << name;
}

TEST(BvhBuild, FlattenedInDepthFirstPairOrder) {
  // Above the flattening's parallel subtrees (2^15 slots), with leaves of several primitives.
  const Inputs in = inputs_of(random_soup(70000, 22, 0.01f));
  expect_depth_first_pairs(build_with<BvhSahConfig>(in, 2), "bvh-sah");
  expect_depth_first_pairs(build_with<BvhSweepConfig>(in, 2), "bvh-sweep");
  expect_depth_first_pairs(build_with<BvhMedianConfig>(in, 2), "bvh-median");
}

/// True when two arrays hold the same bytes.
template <class A>
bool same_bytes(const A& a, const A& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
}

TEST(BvhBuild, BinnedSlotLayoutAndCollapseFromSlotsKeepTheTree) {
  // The binned builder lays serial subtrees out compactly and parallel ones in gapped slots: with every
  // node above the parallel threshold or every node below it, the flattened tree and the leaf order are
  // the same, and either collapse straight from the slots is that collapse of the flattened tree.
  const Inputs in = inputs_of(random_soup(20000, 23, 0.02f));
  BvhSahConfig compact, gapped;
  compact.parallel_threshold = size_t(1) << 30;
  gapped.parallel_threshold = 2;
  const BvhBuildResult a = build_bvh(compact, in.bounds, in.centroids);
  const BvhBuildResult b = build_bvh(gapped, in.bounds, in.centroids);
  EXPECT_TRUE(same_bytes(a.nodes, b.nodes));
  EXPECT_EQ(a.order, b.order);
  for (const BvhSahConfig& config : {compact, gapped}) {
    const BvhSlotsResult slots = build_bvh_slots(config, in.bounds);
    EXPECT_EQ(slots.order, a.order);
    for (const BvhCollapse method : {BvhCollapse::greedy, BvhCollapse::optimal})
      EXPECT_TRUE(same_bytes(collapse_to_bvh8(slots.slots, method), collapse_to_bvh8(a.nodes, method)));
  }
  EXPECT_FALSE(same_bytes(collapse_to_bvh8(a.nodes, BvhCollapse::greedy),
                          collapse_to_bvh8(a.nodes, BvhCollapse::optimal)));
}

TEST(BvhBuild, BinnedChildBoxesAreTightAndLeavesAPermutation) {
  const Mesh mesh = random_soup(5000, 8, 0.05f);
  const Inputs in = inputs_of(mesh);
  BvhSahConfig config;
  const BvhBuildResult r = build_bvh(config, in.bounds, in.centroids);
  std::vector<int> seen(mesh.size(), 0);
  // Each node's box is exactly the union of its children's (or its primitives') boxes.
  for (size_t i = 0; i < r.nodes.size(); ++i) {
    if (i == 1) continue;
    const BvhNode& n = r.nodes[i];
    AABB u;
    if (n.is_leaf()) {
      EXPECT_LE(n.count, uint32_t(config.max_leaf_size));
      for (uint32_t k = n.offset; k < n.offset + n.count; ++k)
        u.extend(in.bounds[r.order[k]]), ++seen[r.order[k]];
    } else {
      u.extend(r.nodes[n.offset].box());
      u.extend(r.nodes[n.offset + 1].box());
    }
    const AABB box = n.box();
    EXPECT_EQ(std::memcmp(&u, &box, sizeof(AABB)), 0) << i;
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int s) { return s == 1; }));
}

TEST(BvhBuild, CoincidentCentroidsAreSplitByForce) {
  Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  for (int i = 0; i < 50; ++i) mesh.triangles.push_back(i % 2 ? glm::uvec3{0, 1, 2} : glm::uvec3{0, 3, 4});
  const Inputs in = inputs_of(mesh);  // two centroids, 25 primitives on each
  auto check = [&](auto config, const char* name) {
    config.max_leaf_size = 4;
    const BuildStats stats = stats_of(build_bvh(config, in.bounds, in.centroids));
    EXPECT_LE(stats.leaf_size_histogram.rbegin()->first, 4u) << name;
    EXPECT_EQ(stats.references, mesh.size());
  };
  check(BvhSahConfig{}, "bvh-sah");
  check(BvhSweepConfig{}, "bvh-sweep");
}

}  // namespace
}  // namespace ab
