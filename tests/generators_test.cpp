// Mesh generators: deterministic by seed, the target triangle count, finite geometry, parameters.
#include "datasets/generators.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <set>

#include "accel/core/error.h"
#include "accel/core/memory.h"

namespace ab {
namespace {

/// Every coordinate finite, every index in range, and the bounds not empty.
void expect_valid(const Mesh& m, const std::string& name) {
  for (const vec3& p : m.vertices)
    ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << name;
  for (const glm::uvec3& t : m.triangles)
    ASSERT_TRUE(t.x < m.vertices.size() && t.y < m.vertices.size() && t.z < m.vertices.size()) << name;
  if (m.size() > 0) {
    EXPECT_FALSE(m.bounds().empty()) << name;
  }
}

/// Parameters from key/value pairs.
Params with(std::map<std::string, std::string> values) {
  return Params(std::move(values));
}

bool same_mesh(const Mesh& a, const Mesh& b) {
  return a.vertices == b.vertices && a.triangles == b.triangles;
}

TEST(Generators, ListHasTheRequiredNamesWithDescriptions) {
  std::set<std::string> names;
  for (const GeneratorInfo& g : generators()) {
    names.insert(g.name);
    EXPECT_FALSE(g.description.empty()) << g.name;
  }
  for (const char* n : {"sphereflake", "terrain", "tetra", "soup", "stadium", "slivers", "cityscape"})
    EXPECT_TRUE(names.count(n)) << n;
}

TEST(Generators, TriangleCountMatchesTheTarget) {
  for (const GeneratorInfo& g : generators())
    for (uint64_t n : {1ull, 2ull, 3ull, 7ull, 12ull, 13ull, 50ull, 333ull, 1000ull, 4097ull, 100000ull}) {
      const Mesh m = generate_mesh(g.name, n, 1, Params());
      SCOPED_TRACE(g.name + " " + std::to_string(n));
      EXPECT_GE(m.size(), 1u);
      EXPECT_LE(std::fabs(static_cast<double>(m.size()) - static_cast<double>(n)),
                0.02 * static_cast<double>(n));
      expect_valid(m, g.name);
    }
}

TEST(Generators, ZeroTrianglesGivesAnEmptyMesh) {
  for (const GeneratorInfo& g : generators()) {
    const Mesh m = generate_mesh(g.name, 0, 1, Params());
    EXPECT_EQ(m.size(), 0u) << g.name;
    EXPECT_TRUE(m.vertices.empty()) << g.name;
  }
}

TEST(Generators, DeterministicBySeed) {
  for (const GeneratorInfo& g : generators()) {
    const Mesh a = generate_mesh(g.name, 5000, 42, Params());
    const Mesh b = generate_mesh(g.name, 5000, 42, Params());
    EXPECT_TRUE(same_mesh(a, b)) << g.name;
  }
  // Generators that use randomness give different meshes for different seeds.
  for (const char* name : {"terrain", "soup", "slivers", "cityscape"}) {
    const Mesh a = generate_mesh(name, 5000, 1, Params());
    const Mesh b = generate_mesh(name, 5000, 2, Params());
    EXPECT_FALSE(same_mesh(a, b)) << name;
  }
}

TEST(Generators, UnknownNameAndParameters) {
  EXPECT_THROW(generate_mesh("nope", 10, 1, Params()), InputError);
  EXPECT_THROW(generate_mesh("soup", 10, 1, with({{"bogus", "1"}})), ParamError);
  EXPECT_THROW(generate_mesh("terrain", 10, 1, with({{"roughness", "2"}})), ParamError);
  EXPECT_THROW(generate_mesh("sphereflake", 10, 1, with({{"depth", "x"}})), ParamError);
}

TEST(Generators, ParametersChangeTheMesh) {
  const Mesh a = generate_mesh("terrain", 2000, 3, with({{"roughness", "0.2"}}));
  const Mesh b = generate_mesh("terrain", 2000, 3, with({{"roughness", "0.8"}}));
  EXPECT_FALSE(same_mesh(a, b));
  const Mesh flat = generate_mesh("sphereflake", 5000, 0, with({{"depth", "0"}}));
  const Mesh deep = generate_mesh("sphereflake", 5000, 0, with({{"depth", "2"}}));
  EXPECT_LT(flat.bounds().extent().x, deep.bounds().extent().x);
  EXPECT_EQ(deep.size(), 5000u);
}

// Found by fuzzing the scene reader (a sphereflake of 200 triangles at depth 7 took over 10 s): a given
// depth asks for millions of spheres or tetrahedra, but the work stays bounded by the triangle count.
TEST(Generators, AGivenDepthDoesNotOutgrowTheCount) {
  for (const auto& [name, depth] : {std::pair{"sphereflake", "7"}, {"stadium", "7"}, {"tetra", "13"}}) {
    const HeapPeak peak;
    const Mesh m = generate_mesh(name, 200, 1, with({{"depth", depth}}));
    EXPECT_EQ(m.size(), 200u) << name;
    expect_valid(m, name);
    if (heap_accounting_enabled()) {
      EXPECT_LT(peak.bytes(), 1u << 20) << name;
    }
  }
}

TEST(Generators, CityscapeHasLatticeCoordinatesDuplicatesAndDegenerates) {
  const Mesh m = generate_mesh("cityscape", 20000, 7, Params());
  for (const vec3& p : m.vertices) {
    // Every coordinate is on the half-unit lattice (roof-edge midpoints of the degenerates).
    EXPECT_EQ(p.x * 2.0f, std::floor(p.x * 2.0f));
    EXPECT_EQ(p.y, std::floor(p.y));
    EXPECT_EQ(p.z, std::floor(p.z));
  }
  size_t zero_area = 0, duplicates = 0;
  std::set<std::array<float, 9>> seen;
  for (size_t i = 0; i < m.size(); ++i) {
    const Triangle t = m.triangle(i);
    if (glm::cross(t.v1 - t.v0, t.v2 - t.v0) == vec3(0.0f)) ++zero_area;
    duplicates +=
        !seen.insert({t.v0.x, t.v0.y, t.v0.z, t.v1.x, t.v1.y, t.v1.z, t.v2.x, t.v2.y, t.v2.z}).second;
  }
  EXPECT_GT(zero_area, 0u);
  EXPECT_GT(duplicates, 0u);
  const Mesh clean = generate_mesh("cityscape", 20000, 7, with({{"degenerate", "false"}}));
  for (size_t i = 0; i < clean.size(); ++i) {
    const Triangle t = clean.triangle(i);
    EXPECT_NE(glm::cross(t.v1 - t.v0, t.v2 - t.v0), vec3(0.0f));
  }
}

TEST(Generators, OnlyCityscapeAndMixedHaveZeroAreaTriangles) {
  for (const GeneratorInfo& g : generators()) {
    if (g.name == "cityscape" || g.name == "mixed") continue;  // degenerate triangles by design
    const Mesh m = generate_mesh(g.name, 20000, 3, Params());
    size_t zero_area = 0;
    for (size_t i = 0; i < m.size(); ++i) {
      const Triangle t = m.triangle(i);
      zero_area += glm::cross(t.v1 - t.v0, t.v2 - t.v0) == vec3(0.0f);
    }
    EXPECT_EQ(zero_area, 0u) << g.name;
  }
}

TEST(Generators, StadiumObjectIsTinyAndHoldsMostTriangles) {
  const Mesh m = generate_mesh("stadium", 10000, 0, Params());
  const AABB room = m.bounds();
  AABB object;
  size_t small = 0;
  for (size_t i = 0; i < m.size(); ++i) {
    const AABB b = m.triangle(i).bounds();
    if (glm::length(b.extent()) < 0.05f * glm::length(room.extent())) {
      ++small;
      object.extend(b);
    }
  }
  EXPECT_GT(small, m.size() * 99 / 100);
  EXPECT_LT(glm::length(object.extent()), 0.05f * glm::length(room.extent()));
}

TEST(Generators, TenMillionTrianglesQuickly) {
  // One large case to keep the "fast for 10M" promise honest without slowing the suite much.
  const Mesh m = generate_mesh("terrain", 10000000, 1, Params());
  EXPECT_EQ(m.size(), 10000000u);
}

}  // namespace
}  // namespace ab
