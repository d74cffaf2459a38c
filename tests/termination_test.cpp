// Termination rules of the space-partitioning trees (issue 11): on hostile inputs (large overlapping
// triangles, fans, degenerate mixes) the octree and kdtree-median keep their references bounded (bad
// refines, pbrt-v3; the reference budget as a safety net, reported as extra.budget_exhausted) and still
// give brute's hits; the octree's depth limit grows with log N.
#include <gtest/gtest.h>

#include <string>

#include "accel/common/depth_limit.h"
#include "accel/core/registry.h"
#include "datasets/generators.h"
#include "structure_test_helpers.h"

namespace ab {
namespace {

using testing::adversarial_rays;
using testing::count_differences;
using testing::random_soup;

std::unique_ptr<Accelerator> built(const std::string& name, const Mesh& mesh,
                                   std::map<std::string, std::string> params = {}) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(mesh));
  auto accel = make_accelerator(name, prims, Params(std::move(params)));
  accel->build();
  return accel;
}

const char* const kBounded[] = {"octree", "kdtree-median"};

TEST(Termination, OctreeDepthLimitGrowsWithLogN) {
  EXPECT_EQ(auto_octree_depth_limit(100000), 10);
  EXPECT_EQ(auto_octree_depth_limit(10000000), 13);
  const Mesh mesh = random_soup(5000, 3, 0.01f);
  EXPECT_EQ(built("octree", mesh, {{"max_depth", "2"}})->stats().extra["depth_limit"],
            std::max(2, auto_octree_depth_limit(5000)));
  EXPECT_EQ(built("octree", mesh, {{"max_depth", "2"}, {"auto_depth", "off"}})->stats().extra["depth_limit"],
            2);
  EXPECT_EQ(built("octree", mesh, {{"max_depth", "15"}})->stats().extra["depth_limit"], 15);
}

TEST(Termination, HostileInputsKeepReferencesBounded) {
  for (const char* gen : {"large", "fan", "mixed"}) {
    const Mesh mesh = generate_mesh(gen, 20000, 1, Params());
    for (const char* name : kBounded) {
      const BuildStats s = built(name, mesh)->stats();
      EXPECT_LE(s.references, 64 * s.primitives) << gen << " " << name;
      EXPECT_LT(s.build_seconds, 30.0) << gen << " " << name;
    }
  }
}

TEST(Termination, BudgetIsASafetyNetReportedInTheStatistics) {
  const Mesh hostile = generate_mesh("mixed", 3000, 2, Params());
  const Mesh tame = random_soup(3000, 4, 0.01f);
  for (const char* name : kBounded) {
    const std::map<std::string, std::string> tight{{"ref_budget", "1.5"}, {"bad_refines", "0"}};
    const BuildStats s = built(name, hostile, tight)->stats();
    EXPECT_LE(double(s.references), 1.5 * double(s.primitives)) << name;
    EXPECT_EQ(s.extra["budget_exhausted"], true) << name;
    EXPECT_EQ(built(name, tame)->stats().extra["budget_exhausted"], false) << name;
    EXPECT_EQ(count_differences(name, hostile, adversarial_rays(hostile, 1500, 3), tight), 0u) << name;
  }
}

TEST(Termination, BadRefinesStopLargeTrianglesAmongDegenerateOnes) {
  const Mesh mesh = generate_mesh("mixed", 3000, 5, Params());
  for (const char* name : kBounded) {
    const std::map<std::string, std::string> off{{"bad_refines", "0"}, {"ref_budget", "1000"}};
    const uint64_t with = built(name, mesh)->stats().references;
    const uint64_t without = built(name, mesh, off)->stats().references;
    EXPECT_LT(with, without) << name;
  }
}

TEST(Termination, RejectsBadTerminationParameters) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(random_soup(10, 1)));
  for (const char* name : kBounded) {
    EXPECT_THROW(make_accelerator(name, prims, testing::make_params({{"ref_budget", "0.5"}})), ParamError);
    EXPECT_THROW(make_accelerator(name, prims, testing::make_params({{"bad_refines", "-1"}})), ParamError);
  }
}

}  // namespace
}  // namespace ab
