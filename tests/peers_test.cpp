// The outside peers (cgal, bullet) against brute force: registered as references, their hits in the
// contract's form and classified (agree, tie, edge, graze, limit) with none unexplained on every generator,
// ray kind and the scanned meshes; degenerate triangles, parallel and backward rays, tmin/tmax segments,
// any hit, empty meshes. Each test skips a peer that CMake did not find.
#include <gtest/gtest.h>

#include <filesystem>

#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "datasets/generators.h"
#include "datasets/mesh_io.h"
#include "datasets/rays.h"
#include "harness/compare.h"
#include "harness/run.h"
#include "harness/selection.h"
#include "harness/suite.h"
#include "harness/target.h"
#include "harness/verification.h"

namespace ab {
namespace {

const std::vector<std::string> kPeers{"cgal", "bullet"};

/// The peers this build has (CMake builds each only when its package is found).
std::vector<std::string> built_peers() {
  std::vector<std::string> out;
  for (const auto& p : kPeers)
    if (is_registered(p)) out.push_back(p);
  return out;
}

std::unique_ptr<Accelerator> built(const Target& target, const std::string& name) {
  auto a = make_target_accelerator(target, name, Params{});
  a->build();
  return a;
}

std::vector<Hit> trace(const Accelerator& a, const std::vector<Ray>& rays) {
  std::vector<Hit> hits(rays.size());
  trace_closest(a, rays, hits, 2);
  return hits;
}

/// Classifies the peer's hits against `truth` (brute force or a structure identical to it) as verify does.
Agreement classify(const Target& target, const std::string& peer, const std::vector<Ray>& rays,
                   const std::vector<Hit>& truth) {
  const auto a = built(target, peer);
  return classify_agreement(rays, truth, trace(*a, rays), hit_triangles(target));
}

Target small_mesh(std::vector<vec3> v, std::vector<glm::uvec3> t) {
  auto mesh = std::make_shared<Mesh>();
  mesh->vertices = std::move(v);
  mesh->triangles = std::move(t);
  return mesh_target(mesh, "test");
}

Ray ray(vec3 org, vec3 dir, float tmin = 0.0f, float tmax = kInf) {
  Ray r;
  r.org = org;
  r.dir = dir;
  r.tmin = tmin;
  r.tmax = tmax;
  return r;
}

TEST(Peers, AreRegisteredAsReferencesAndClassifiedNotHeldToBytes) {
  if (built_peers().empty()) GTEST_SKIP() << "neither CGAL nor Bullet was found at build time";
  for (const auto& p : built_peers()) {
    EXPECT_TRUE(find_accelerator(p).is_reference) << p;
    EXPECT_FALSE(is_exact(p)) << p;
    EXPECT_FALSE(find_accelerator(p).make_for_instances) << p << " over meshes only";
  }
  EXPECT_TRUE(is_exact("brute"));
  EXPECT_TRUE(is_exact("bvh-sah"));
}

TEST(Peers, AgreeWithBruteOnEveryGeneratorAndRayKind) {
  for (const auto& peer : built_peers()) {
    for (const auto& gen : generators()) {
      const Target target =
          mesh_target(std::make_shared<const Mesh>(generate_mesh(gen.name, 3000, 2, Params{})), gen.name);
      const auto brute = built(target, "brute");
      const RayTarget rt = ray_target(target);
      for (const auto& kind : ray_kinds()) {
        const std::vector<Ray> rays = make_rays(kind.name, rt, 1000, 9);
        const Agreement a = classify(target, peer, rays, trace(*brute, rays));
        EXPECT_EQ(a.unexplained, 0u) << peer << " / " << gen.name << " / " << kind.name
                                     << ": first unexplained ray "
                                     << (a.unexplained_rays.empty() ? 0 : a.unexplained_rays.front());
        // Ties count with agreement (coplanar stacks are ties by construction).
        EXPECT_GT(a.agree + a.tie, rays.size() * 9 / 10) << peer << " / " << gen.name << " / " << kind.name;
      }
    }
  }
}

TEST(Peers, AgreeWithBruteOnTheScannedMeshes) {
  const std::filesystem::path dir(ACCELBENCH_SOURCE_DIR "/../shared/meshes");
  if (!std::filesystem::exists(dir / "stanford-bunny.obj")) GTEST_SKIP() << "../shared/meshes is absent";
  for (const char* file : {"stanford-bunny.obj", "teapot.obj"}) {
    const Target target = load_target((dir / file).string(), "");
    const auto sah = built(target, "bvh-sah");  // identical to brute force (the contract), and fast
    const RayTarget rt = ray_target(target);
    for (const char* kind : {"primary", "incoherent"}) {
      const std::vector<Ray> rays = make_rays(kind, rt, 2000, 3);
      const std::vector<Hit> truth = trace(*sah, rays);
      for (const auto& peer : built_peers()) {
        const Agreement a = classify(target, peer, rays, truth);
        EXPECT_EQ(a.unexplained, 0u) << peer << " / " << file << " / " << kind;
        EXPECT_GT(a.agree, rays.size() * 9 / 10) << peer << " / " << file << " / " << kind;
      }
    }
  }
}

TEST(Peers, DegenerateTrianglesNeverHitAndKeepTheirIds) {
  // 0: collinear, 1: a repeated vertex, 2: a point, 3: a regular triangle under all three.
  const Target target = small_mesh({{0, 0, 1},
                                    {1, 0, 1},
                                    {2, 0, 1},
                                    {0.5f, 0.5f, 1},
                                    {0.25f, 0.25f, 1},
                                    {-1, -1, 0},
                                    {3, -1, 0},
                                    {-1, 3, 0}},
                                   {{0, 1, 2}, {0, 0, 3}, {4, 4, 4}, {5, 6, 7}});
  for (const auto& peer : built_peers()) {
    const auto a = built(target, peer);
    for (const vec3 org : {vec3(0.5f, 0, 2), vec3(0.25f, 0.25f, 2), vec3(0.2f, 0.1f, 2)}) {
      Hit h;
      a->intersect_one(ray(org, {0, 0, -1}), h, kInvalidId, nullptr);
      EXPECT_EQ(h.prim, 3u) << peer << " at " << org.x << "," << org.y;
      EXPECT_FLOAT_EQ(h.t, 2.0f) << peer;
    }
  }
}

TEST(Peers, ParallelBackwardAndZeroRaysMiss) {
  const Target target = small_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  for (const auto& peer : built_peers()) {
    const auto a = built(target, peer);
    const std::vector<Ray> rays{ray({-1, 0.25f, 0}, {1, 0, 0}),       // in the triangle's plane
                                ray({0.25f, 0.25f, 1}, {1, 0, 0}),    // parallel above it
                                ray({0.25f, 0.25f, 1}, {0, 0, 1}),    // going away
                                ray({0.25f, 0.25f, -1}, {0, 0, -1}),  // behind, going away
                                ray({0.25f, 0.25f, 1}, {0, 0, 0})};   // zero direction
    const std::vector<Hit> hits = trace(*a, rays);
    for (size_t i = 0; i < hits.size(); ++i) EXPECT_FALSE(hits[i].found()) << peer << " ray " << i;
  }
}

TEST(Peers, HitsFollowTheContractWithinTminAndTmax) {
  const Target target = small_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  const auto brute = built(target, "brute");
  // Unnormalized direction (t = 0.5 at the triangle), segments on both sides of the hit, and onto it.
  const std::vector<Ray> rays{
      ray({0.25f, 0.125f, 1}, {0, 0, -2}),          ray({0.25f, 0.125f, 1}, {0, 0, -1}, 0.5f, 2),
      ray({0.25f, 0.125f, 1}, {0, 0, -1}, 0, 0.5f), ray({0.25f, 0.125f, 1}, {0, 0, -1}, 1.5f, 3),
      ray({0.25f, 0.125f, 1}, {0, 0, -1}, 1, 1),    ray({0.25f, 0.125f, 1}, {0, 0, -1}, 0, 1),
      ray({0.25f, 0.125f, 1}, {0, 0, -1}, 2, 1)};
  const std::vector<Hit> truth = trace(*brute, rays);
  ASSERT_TRUE(truth[0].found());
  EXPECT_FLOAT_EQ(truth[0].t, 0.5f);
  for (const auto& peer : built_peers()) {
    const std::vector<Hit> hits = trace(*built(target, peer), rays);
    for (size_t i = 0; i < rays.size(); ++i) {
      EXPECT_EQ(hits[i].found(), truth[i].found()) << peer << " ray " << i;
      if (!truth[i].found()) continue;
      EXPECT_EQ(hits[i].t, truth[i].t) << peer << " ray " << i;  // the project's kernel: brute's bits
      EXPECT_EQ(hits[i].u, truth[i].u) << peer << " ray " << i;
      EXPECT_EQ(hits[i].v, truth[i].v) << peer << " ray " << i;
      EXPECT_EQ(hits[i].inst, kInvalidId) << peer;
    }
  }
}

TEST(Peers, AnyHitMatchesWhetherBruteFindsAHit) {
  const Target target =
      mesh_target(std::make_shared<const Mesh>(generate_mesh("sphereflake", 3000, 1, Params{})), "flake");
  const auto brute = built(target, "brute");
  const RayTarget rt = ray_target(target);
  for (const char* kind : {"shadow", "incoherent"}) {
    const std::vector<Ray> rays = make_rays(kind, rt, 1000, 5);
    const std::vector<Hit> truth = trace(*brute, rays);
    for (const auto& peer : built_peers()) {
      const auto a = built(target, peer);
      std::vector<uint8_t> out(rays.size());
      trace_occluded(*a, rays, out, 2);
      size_t differ = 0;
      for (size_t i = 0; i < rays.size(); ++i) differ += (out[i] != 0) != truth[i].found();
      EXPECT_LE(differ, rays.size() / 100) << peer << " / " << kind;  // grazing and limit cases only
    }
  }
}

TEST(Peers, AnyHitHonoursTminAndTmax) {
  const Target target = small_mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  const std::vector<Ray> rays{
      ray({0.25f, 0.125f, 1}, {0, 0, -1}, 0, 2), ray({0.25f, 0.125f, 1}, {0, 0, -1}, 0, 0.5f),
      ray({0.25f, 0.125f, 1}, {0, 0, -1}, 1.5f, 3), ray({0.25f, 0.125f, 1}, {0, 0, -1}, 2, 0.5f),
      ray({0.25f, 0.125f, 1}, {0, 0, -1}, 1, 1)};
  const std::vector<uint8_t> expected{1, 0, 0, 0, 1};
  for (const auto& peer : built_peers()) {
    std::vector<uint8_t> out(rays.size());
    trace_occluded(*built(target, peer), rays, out, 1);
    EXPECT_EQ(out, expected) << peer;
  }
}

TEST(Peers, EmptyMeshBuildsAndMisses) {
  const Target target = small_mesh({}, {});
  for (const auto& peer : built_peers()) {
    const auto a = built(target, peer);
    const std::vector<Hit> hits = trace(*a, {ray({0, 0, 1}, {0, 0, -1})});
    EXPECT_FALSE(hits[0].found()) << peer;
    std::vector<uint8_t> out(1, 1);
    const std::vector<Ray> rays{ray({0, 0, 1}, {0, 0, -1})};
    trace_occluded(*a, rays, out, 1);
    EXPECT_EQ(out[0], 0) << peer;
  }
}

TEST(Peers, StatisticsSayWhatIsMeasured) {
  const Target target =
      mesh_target(std::make_shared<const Mesh>(generate_mesh("terrain", 2000, 1, Params{})), "terrain");
  for (const auto& peer : built_peers()) {
    const auto a = built(target, peer);
    const BuildStats& s = a->stats();
    EXPECT_EQ(s.primitives, target.triangles) << peer;
    EXPECT_GT(s.nodes, 0u) << peer;
    EXPECT_GT(s.bytes, 0u) << peer;
    EXPECT_TRUE(s.extra.contains("note")) << peer;
    EXPECT_GT(s.build_seconds, 0.0) << peer;
  }
}

TEST(Peers, ASuiteTimesThemAndClassifiesTheirHits) {
  if (built_peers().empty()) GTEST_SKIP() << "neither CGAL nor Bullet was found at build time";
  nlohmann::json j = nlohmann::json::parse(R"({
    "repetitions": 2, "warmup": 0, "min_time": 0, "threads": [1],
    "scenes": [{"generator": "sphereflake", "triangles": 2000}],
    "rays": [{"kind": "primary", "count": 256}, {"kind": "shadow", "count": 256}],
    "verify": {"brute_rays": 0, "reference": "bvh-sah", "embree": true}})");
  j["accelerators"] = {"embree", "bvh-sah"};
  for (const auto& p : built_peers()) j["accelerators"].push_back(p);
  const auto dir =
      std::filesystem::temp_directory_path() / ("accelbench_peers_" + std::to_string(::getpid()));
  RunOptions options;
  options.out_dir = dir.string();
  const nlohmann::json report = run_suite(parse_suite(j, "peers.json", ""), options);
  std::filesystem::remove_all(dir);
  EXPECT_TRUE(report["verified"].get<bool>()) << report["failures"].dump();
  std::map<std::string, int> rows;
  for (const auto& r : report["results"]) {
    const std::string name = r["accelerator"];
    ++rows[name];
    if (name != "cgal" && name != "bullet") continue;
    EXPECT_EQ(r["classified_against"], "bvh-sah") << name;
    EXPECT_EQ(r["embree_unexplained"], 0) << name;
    EXPECT_FALSE(r.contains("brute_mismatches")) << name << " is classified, not held to bytes";
    EXPECT_TRUE(r["ratio_to_embree"].is_number()) << name;
    EXPECT_EQ(r["seconds_samples"].size(), 2u) << name;
  }
  for (const auto& p : built_peers()) EXPECT_EQ(rows[p], 3) << p;  // primary, shadow closest and any
}

TEST(Peers, SuitesNameThemAndValidate) {
  const Suite million = read_suite(ACCELBENCH_SOURCE_DIR "/suites/peers-million.json");
  const bool both = built_peers().size() == kPeers.size();
  if (both) {
    EXPECT_NO_THROW(validate_suite(million));
  }
  if (!std::filesystem::exists(ACCELBENCH_SOURCE_DIR "/../shared/meshes/stanford-bunny.obj")) return;
  const Suite peers = read_suite(ACCELBENCH_SOURCE_DIR "/suites/peers.json");
  if (both) {
    EXPECT_NO_THROW(validate_suite(peers));
  }
  std::set<std::string> names;
  for (const auto& a : peers.accelerators) names.insert(a.name);
  for (const auto& info : accelerators())
    if (info.name != "brute" && !is_test_only(info.name)) {
      EXPECT_EQ(names.count(info.name), 1u) << info.name;
    }
}

}  // namespace
}  // namespace ab
