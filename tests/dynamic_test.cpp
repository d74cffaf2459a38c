// Per-frame updates (issue 13, part 2): refitted BVH boxes are exactly the union of their triangles' new
// bounds (binary and 8-wide, every builder), refitted BVHs and every structure under every strategy give hits
// byte-identical to brute on several frames of a rigid, a deforming and an exploding scene at 1 and 2
// threads, adaptive rebuilds once its threshold is crossed, and Embree's dynamic commit agrees with brute.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <tbb/task_arena.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "accel/bvh/bvh.h"
#include "accel/core/error.h"
#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "accel/reference/embree.h"
#include "datasets/generators.h"
#include "harness/run.h"
#include "harness/suite.h"
#include "tracer/deform.h"
#include "tracer/sampling.h"
#include "tracer/scene.h"
#include "tracer/scene_accel.h"
#include "tracer/update_strategy.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

/// Rays from inside and outside the bounds towards random points of them.
std::vector<Ray> rays_into(const AABB& b, size_t n, uint64_t seed = 5) {
  std::vector<Ray> rays;
  Rng rng(seed, 1);
  auto point = [&] { return b.lo + vec3(rng.uniform(), rng.uniform(), rng.uniform()) * b.extent(); };
  for (size_t i = 0; i < n; ++i) {
    Ray r;
    r.org = i % 3 ? point() : b.center() + vec3(0, 0, 3.0f * glm::length(b.extent()));
    r.dir = point() - r.org;
    if (i % 13 == 0) r.dir = vec3(1, 0, 0);
    rays.push_back(r);
  }
  return rays;
}

/// A mesh exploded (or waved) by phase p.
std::shared_ptr<const Mesh> deformed(const Mesh& base, Deformer::Kind kind, float p) {
  Deformer d;
  d.kind = kind;
  return std::make_shared<Mesh>(d.apply(base, p));
}

/// Closest hits of `accel` over rays at `threads` threads.
std::vector<Hit> hits_of(const Accelerator& accel, const std::vector<Ray>& rays, int threads) {
  std::vector<Hit> hits(rays.size());
  trace_closest(accel, rays, hits, threads);
  return hits;
}

bool same_hits(const std::vector<Hit>& a, const std::vector<Hit>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Hit)) == 0;
}

/// Checks every binary node box is exactly the union of its leaf triangles' (leaves) or children's boxes.
template <class B>
void expect_tight_binary(const B& bvh, const TrianglePrims& prims) {
  const BvhNodeArray& nodes = bvh.nodes();
  for (size_t i = nodes.size(); i-- > 0;) {
    if (i == 1) continue;
    AABB want;
    if (nodes[i].is_leaf()) {
      for (uint32_t k = 0; k < nodes[i].count; ++k)
        want.extend(prims.bounds(bvh.order()[nodes[i].offset + k]));
    } else {
      want.extend(nodes[nodes[i].offset].box());
      want.extend(nodes[nodes[i].offset + 1].box());
    }
    ASSERT_EQ(nodes[i].box().lo, want.lo) << i;
    ASSERT_EQ(nodes[i].box().hi, want.hi) << i;
  }
}

/// Checks every wide leaf lane's box is exactly the union of its block lanes' triangles.
template <class B>
void expect_tight_wide(const B& bvh, const TrianglePrims& prims) {
  for (const Bvh8Node& node : bvh.wide_nodes())
    for (int k = 0; k < Bvh8Node::kWidth; ++k) {
      if (node.count[k] == 0) continue;
      AABB want;
      for (uint32_t j = 0; j < node.count[k]; ++j)
        want.extend(prims.bounds(bvh.block_ids()[4 * node.child[k] + j]));
      ASSERT_EQ(node.box(k).lo, want.lo);
      ASSERT_EQ(node.box(k).hi, want.hi);
    }
}

template <class B>
void check_refit(const typename B::Config& config, int width) {
  const Mesh base = generate_mesh("sphereflake", 3000, 1, {});
  auto prims0 = std::make_shared<TrianglePrims>(std::make_shared<Mesh>(base));
  B bvh(prims0, config);
  bvh.build();
  for (Deformer::Kind kind : {Deformer::Kind::kWave, Deformer::Kind::kExplode})
    for (float p : {0.3f, 1.0f}) {
      auto prims = std::make_shared<TrianglePrims>(deformed(base, kind, p));
      ASSERT_TRUE(bvh.refit(prims));
      if (width == 2) expect_tight_binary(bvh, *prims);
      if (width == 8) expect_tight_wide(bvh, *prims);
      auto brute = make_accelerator("brute", prims, {});
      brute->build();
      const std::vector<Ray> rays = rays_into(prims->bounds(), 1500);
      const std::vector<Hit> expected = hits_of(*brute, rays, 1);
      for (int threads : {1, 2})
        EXPECT_TRUE(same_hits(hits_of(bvh, rays, threads), expected)) << "width " << width << " p " << p;
    }
  // A different triangle count is refused and leaves the structure as it was.
  EXPECT_FALSE(bvh.refit(std::make_shared<TrianglePrims>(std::make_shared<Mesh>())));
}

TEST(Refit, EveryBuilderBothWidthsKeepsBoxesTightAndHitsIdentical) {
  for (int width : {2, 8}) {
    BvhSahConfig sah;
    sah.width = width;
    check_refit<BvhSah<TrianglePrims>>(sah, width);
    BvhMedianConfig median;
    median.width = width;
    check_refit<BvhMedian<TrianglePrims>>(median, width);
    BvhSweepConfig sweep;
    sweep.width = width;
    check_refit<BvhSweep<TrianglePrims>>(sweep, width);
  }
}

/// True when the two arrays hold the same bytes.
template <class A>
bool same_bytes(const A& a, const A& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
}

/// A B of the given width over base, built.
template <class B>
std::unique_ptr<B> built_bvh(const Mesh& base, int width) {
  typename B::Config config;
  config.width = width;
  auto bvh = std::make_unique<B>(std::make_shared<TrianglePrims>(std::make_shared<Mesh>(base)), config);
  bvh->build();
  return bvh;
}

/// Refits a to frame sa at 1 thread and b to frame sb at 2 threads; both trees must be the same bytes.
template <class B, class SA, class SB>
void expect_same_refit(B& a, const SA& sa, B& b, const SB& sb) {
  bool ok_a = false, ok_b = false;
  tbb::task_arena(1).execute([&] { ok_a = a.refit(sa); });
  tbb::task_arena(2).execute([&] { ok_b = b.refit(sb); });
  ASSERT_TRUE(ok_a && ok_b);
  ASSERT_TRUE(same_bytes(a.nodes(), b.nodes()));
  ASSERT_TRUE(same_bytes(a.wide_nodes(), b.wide_nodes()));
  ASSERT_TRUE(same_bytes(a.leaf_blocks(), b.leaf_blocks()));
}

/// Refitting straight from the frame's mesh (at 1 thread) gives the tree a refit from its TrianglePrims (at
/// 2) gives, byte for byte, tight, with brute's hits; after it a rebuild and the quality metrics see the
/// frame (its TrianglePrims made then), and a mesh of another triangle count is refused.
template <class B>
void check_refit_from_mesh(int width) {
  const Mesh base = generate_mesh("sphereflake", 3000, 1, {});
  const auto from_mesh = built_bvh<B>(base, width), from_prims = built_bvh<B>(base, width);
  // Refitted to the positions it was built over, the leaf blocks are the build's byte for byte (their terms,
  // made four lanes at once, are the bits the build's packing stores lane by lane).
  const Triangle4Array built_blocks = from_mesh->leaf_blocks();
  ASSERT_TRUE(from_mesh->refit(std::make_shared<const Mesh>(base)));
  EXPECT_TRUE(same_bytes(from_mesh->leaf_blocks(), built_blocks));
  std::shared_ptr<const TrianglePrims> prims;
  for (Deformer::Kind kind : {Deformer::Kind::kWave, Deformer::Kind::kExplode})
    for (float p : {0.3f, 1.0f}) {
      const auto mesh = deformed(base, kind, p);
      prims = std::make_shared<TrianglePrims>(mesh);
      expect_same_refit(*from_mesh, mesh, *from_prims, prims);
      if (::testing::Test::HasFatalFailure()) return;
      if (width == 2) expect_tight_binary(*from_mesh, *prims);
      if (width == 8) expect_tight_wide(*from_mesh, *prims);
      EXPECT_EQ(from_mesh->bounds().lo, prims->bounds().lo);
      EXPECT_EQ(from_mesh->bounds().hi, prims->bounds().hi);
      auto brute = make_accelerator("brute", prims, {});
      brute->build();
      const std::vector<Ray> rays = rays_into(prims->bounds(), 1500);
      const std::vector<Hit> expected = hits_of(*brute, rays, 1);
      for (int threads : {1, 2})
        EXPECT_TRUE(same_hits(hits_of(*from_mesh, rays, threads), expected))
            << "width " << width << " p " << p;
    }
  from_mesh->measure_quality(), from_prims->measure_quality();
  EXPECT_EQ(from_mesh->stats().epo, from_prims->stats().epo);
  from_mesh->build();  // over the last frame: its TrianglePrims is made from the mesh now
  auto brute = make_accelerator("brute", prims, {});
  brute->build();
  const std::vector<Ray> rays = rays_into(prims->bounds(), 1500, 7);
  EXPECT_TRUE(same_hits(hits_of(*from_mesh, rays, 2), hits_of(*brute, rays, 1)));
  EXPECT_FALSE(from_mesh->refit(std::make_shared<const Mesh>()));
}

TEST(Refit, FromTheMeshEqualsFromItsTrianglePrims) {
  for (int width : {2, 8}) {
    check_refit_from_mesh<BvhSah<TrianglePrims>>(width);
    check_refit_from_mesh<BvhMedian<TrianglePrims>>(width);
  }
}

/// Checks every interior lane box of a wide tree is exactly the union of its child node's lanes.
template <class B>
void expect_tight_wide_interior(const B& bvh) {
  const Bvh8NodeArray& wide = bvh.wide_nodes();
  for (const Bvh8Node& node : wide)
    for (int k = 0; k < Bvh8Node::kWidth; ++k) {
      if (node.count[k] != 0 || node.child[k] == 0) continue;
      const AABB want = wide_node_box(wide[node.child[k]]);
      ASSERT_EQ(node.box(k).lo, want.lo);
      ASSERT_EQ(node.box(k).hi, want.hi);
    }
}

/// The refit by parallel subtrees (refit.h: a serial descent picks subtrees of bounded size, a parallel loop
/// refits each in one task, the nodes above them last) gives the serial refit's tree byte for byte on a tree
/// of many tasks, every box the union of its triangles' or children's, and brute's hits.
template <class B>
void check_refit_by_subtrees(int width) {
  const Mesh base = generate_mesh("sphereflake", 40000, 1, {});
  const auto serial = built_bvh<B>(base, width), parallel = built_bvh<B>(base, width);
  const size_t nodes = width == 8 ? parallel->wide_nodes().size() : parallel->nodes().size();
  ASSERT_GT(nodes, 8 * (width == 8 ? kRefitTaskNodesWide : kRefitTaskNodesBinary));  // many tasks
  for (Deformer::Kind kind : {Deformer::Kind::kWave, Deformer::Kind::kExplode}) {
    const auto mesh = deformed(base, kind, 0.7f);
    expect_same_refit(*serial, mesh, *parallel, mesh);
    if (::testing::Test::HasFatalFailure()) return;
    const auto prims = std::make_shared<TrianglePrims>(mesh);
    if (width == 2) expect_tight_binary(*parallel, *prims);
    if (width == 8) expect_tight_wide(*parallel, *prims), expect_tight_wide_interior(*parallel);
    auto brute = make_accelerator("brute", prims, {});
    brute->build();
    const std::vector<Ray> rays = rays_into(prims->bounds(), 1000);
    EXPECT_TRUE(same_hits(hits_of(*parallel, rays, 2), hits_of(*brute, rays, 1))) << "width " << width;
  }
}

TEST(Refit, ByParallelSubtreesEqualsTheSerialRefit) {
  for (int width : {2, 8}) check_refit_by_subtrees<BvhSah<TrianglePrims>>(width);
}

TEST(Refit, StructuresThatDoNotRefitSayFalse) {
  auto prims = std::make_shared<TrianglePrims>(std::make_shared<Mesh>(generate_mesh("tetra", 64, 1, {})));
  auto grid = make_accelerator("grid", prims, {});
  grid->build();
  EXPECT_FALSE(grid->refit(prims));
  EXPECT_FALSE(grid->refit(std::make_shared<const Mesh>(prims->mesh())));
  EXPECT_TRUE(FrameUpdater::supports("bvh-sah", {}, UpdateStrategy::kRefit));
  EXPECT_FALSE(FrameUpdater::supports("grid", {}, UpdateStrategy::kRefit));
  EXPECT_TRUE(FrameUpdater::supports("grid", {}, UpdateStrategy::kTopLevel));
  EXPECT_FALSE(FrameUpdater::supports("embree", {}, UpdateStrategy::kTopLevel));
}

/// Rigid, deforming and exploding instances over 2..3 time units.
std::string animated_scene_xml() {
  return "<scene>\n<camera><eye>0 3 12</eye><lookat>0 0 0</lookat></camera>\n"
         "<mesh name='flake' generator='sphereflake' triangles='300' seed='3'/>\n"
         "<mesh name='wave' generator='tetra' triangles='256'><deform type='wave' start='2' end='3'>"
         "<amplitude>0.05</amplitude></deform></mesh>\n"
         "<mesh name='boom' generator='sphereflake' triangles='300'><deform type='explode' start='2' "
         "end='3'/></mesh>\n"
         "<instance mesh='flake'><keyframe time='2'><translate>-2 0 0</translate><rotate axis='Y'>0</rotate>"
         "</keyframe><keyframe time='3'><translate>2 1 0</translate><rotate "
         "axis='Y'>270</rotate></keyframe></instance>\n"
         "<instance mesh='wave'/>\n<instance mesh='boom'><translate>0 0 "
         "-1</translate></instance>\n</scene>\n";
}

/// Follows `scene` over `frames` frames with every structure and strategy it supports; each frame's hits must
/// equal brute's on that frame at 1 and 2 threads.
void check_strategies(const Scene& scene, int frames, size_t ray_count,
                      const std::vector<std::string>& names) {
  std::vector<std::shared_ptr<const Scene>> at;
  std::vector<std::vector<Ray>> rays;
  std::vector<std::vector<Hit>> expected;
  for (int f = 0; f < frames; ++f) {
    at.push_back(std::make_shared<const Scene>(scene_at(scene, frame_time(uint64_t(f), uint64_t(frames)))));
    rays.push_back(rays_into(at.back()->world_bounds(), ray_count, uint64_t(f) + 1));
    auto brute = make_scene_accelerator(at.back(), "brute", Params{});
    brute->build();
    expected.push_back(hits_of(*brute, rays.back(), 1));
  }
  for (const std::string& name : names)
    for (UpdateStrategy s : all_update_strategies()) {
      if (!FrameUpdater::supports(name, {}, s)) continue;
      FrameUpdater updater(name, {}, s, 1.2);
      for (int f = 0; f < frames; ++f) {
        const FrameUpdate u = updater.update(at[size_t(f)]);
        if (s != UpdateStrategy::kAdaptive) {
          EXPECT_EQ(u.rebuilt, f == 0 || s == UpdateStrategy::kRebuild);
        }
        for (int threads : {1, 2})
          EXPECT_TRUE(
              same_hits(hits_of(updater.accelerator(), rays[size_t(f)], threads), expected[size_t(f)]))
              << scene.path << " " << name << " " << strategy_name(s) << " frame " << f << " " << threads
              << " threads";
      }
    }
}

/// Every registered structure of the project (not the test doubles, not Embree).
std::vector<std::string> project_structures() {
  std::vector<std::string> names;
  for (const AcceleratorInfo& info : accelerators())
    if (info.make_for_instances && info.name.rfind("test-", 0) != 0 && info.name != "embree")
      names.push_back(info.name);
  return names;
}

TEST(Strategies, EveryStructureAndStrategyMatchesBruteOnEveryFrame) {
  const Scene scene = parse_scene(animated_scene_xml(), "anim.xml", ".");
  check_strategies(scene, 4, 600, project_structures());
}

TEST(Strategies, ShippedAnimationsMatchBruteUnderEveryStrategy) {
  const fs::path dir = fs::path(ACCELBENCH_SOURCE_DIR) / "datasets" / "scenes";
  for (const char* name : {"orbit.xml", "wave.xml", "explode.xml"})
    check_strategies(load_scene((dir / name).string()), 3, 400, {"bvh-sah", "bvh-median", "kdtree-sah"});
}

TEST(Strategies, AdaptiveRebuildsOnceTheThresholdIsCrossed) {
  // The twisting tower of wave.xml: its bounds barely change while its refitted leaves turn and overlap.
  const Scene scene = load_scene(std::string(ACCELBENCH_SOURCE_DIR) + "/datasets/scenes/wave.xml");
  auto run = [&](double threshold) {
    FrameUpdater updater("bvh-sah", {}, UpdateStrategy::kAdaptive, threshold);
    for (uint64_t f = 0; f < 6; ++f) {
      const FrameUpdate u = updater.update(std::make_shared<const Scene>(scene_at(scene, frame_time(f, 6))));
      EXPECT_GT(u.sah_cost, 0.0);
    }
    return updater.rebuilds();
  };
  EXPECT_EQ(run(1e9), 1);     // never: only the first build
  EXPECT_GT(run(1.0001), 1);  // the twist degrades the refitted tree at once
  EXPECT_THROW(parse_strategy("sometimes"), ParamError);
  EXPECT_EQ(parse_strategy("top-level"), UpdateStrategy::kTopLevel);
}

TEST(Strategies, RefitDegradesTheSahCostOfAnExplosionAndRebuildDoesNot) {
  const Scene scene = parse_scene(animated_scene_xml(), "anim.xml", ".");
  FrameUpdater refit("bvh-sah", {}, UpdateStrategy::kRefit), rebuild("bvh-sah", {}, UpdateStrategy::kRebuild);
  double refit_cost = 0.0, rebuild_cost = 0.0;
  for (int f = 0; f < 4; ++f) {
    auto frame = std::make_shared<const Scene>(scene_at(scene, frame_time(f, 4)));
    refit_cost = refit.update(frame).sah_cost;
    rebuild_cost = rebuild.update(frame).sah_cost;
  }
  EXPECT_GT(refit_cost, rebuild_cost);
}

TEST(EmbreeDynamic, RefitAndDynamicRebuildAgreeWithBrute) {
  const Mesh base = generate_mesh("sphereflake", 4000, 1, {});
  auto prims0 = std::make_shared<TrianglePrims>(std::make_shared<Mesh>(base));
  EmbreeMesh embree(prims0, EmbreeConfig{});
  embree.build();
  for (RTCBuildQuality q : {RTC_BUILD_QUALITY_REFIT, RTC_BUILD_QUALITY_LOW})
    for (float p : {0.2f, 0.6f, 1.0f}) {
      auto prims = std::make_shared<TrianglePrims>(deformed(base, Deformer::Kind::kExplode, p));
      if (q == RTC_BUILD_QUALITY_REFIT)
        ASSERT_TRUE(embree.refit(prims));
      else
        embree.commit_frame(prims, q);
      auto brute = make_accelerator("brute", prims, {});
      brute->build();
      const std::vector<Ray> rays = rays_into(prims->bounds(), 2000);
      const std::vector<Hit> a = hits_of(*brute, rays, 1), b = hits_of(embree, rays, 1);
      size_t agree = 0, found = 0;
      for (size_t i = 0; i < rays.size(); ++i) {
        found += a[i].found();
        agree += a[i].found() == b[i].found() && a[i].prim == b[i].prim;
      }
      EXPECT_GT(found, rays.size() / 10);
      EXPECT_GE(agree, rays.size() * 99 / 100) << "quality " << int(q) << " p " << p;
    }
}

/// A folder of its own under the system's temporary folder, removed at the end.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) : path(fs::temp_directory_path() / ("ab_dynamic_" + name)) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

/// A small animated scene file (the rigid, deforming and exploding instances) in dir.
std::string write_scene(const fs::path& dir) {
  const std::string path = (dir / "anim.xml").string();
  std::ofstream(path) << animated_scene_xml();
  return path;
}

TEST(DynamicSuite, BadAnimatedInputNamesTheField) {
  TempDir dir("bad");
  const std::string scene = write_scene(dir.path);
  auto error_of = [&](const std::string& scene_json) {
    const std::string text = R"({"scenes": [)" + scene_json + R"(], "accelerators": ["bvh-sah"],
      "rays": [{"kind": "primary", "count": 8}]})";
    try {
      validate_suite(parse_suite(nlohmann::json::parse(text), "d.json", dir.path.string()));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of(R"({"scene": "anim.xml", "frames": 1})"),
            "d.json: scenes[0].frames: 1 is outside [2, 100000]");
  EXPECT_NE(error_of(R"({"scene": "anim.xml", "frames": 3, "strategies": ["refit", "often"]})")
                .find("d.json: scenes[0].strategies[1]: strategy 'often' is not one of"),
            std::string::npos);
  EXPECT_EQ(error_of(R"({"scene": "anim.xml", "strategies": ["refit"]})"),
            "d.json: scenes[0]: missing field 'frames' (an animated scene's frame count)");
  EXPECT_EQ(error_of(R"({"generator": "soup", "triangles": 10, "frames": 3})"),
            "d.json: scenes[0].frames: unknown field");
  EXPECT_EQ(
      error_of(R"({"scene": "anim.xml", "frames": 3, "threshold": 0.5})"),
      "d.json: scenes[0].threshold: expected a number in (1, 100] (rebuild once the SAH cost grew by this "
      "factor)");
  EXPECT_EQ(error_of(R"({"mesh": "m.obj", "frames": 3})"),
            "d.json: scenes[0]: 'frames' and 'strategies' need an animated 'scene'");
  std::ofstream(dir.path / "static.xml") << "<scene><mesh name='m' generator='tetra' triangles='16'/>"
                                            "<instance mesh='m'/></scene>";
  EXPECT_NE(error_of(R"({"scene": "static.xml", "frames": 3})").find("scenes[0].frames: "),
            std::string::npos);
  EXPECT_NO_THROW(validate_suite(read_suite(std::string(ACCELBENCH_SOURCE_DIR) + "/suites/dynamic.json")));
}

TEST(DynamicSuite, BadAnimatedSuiteExitsTwoWithOneLine) {
  const char* bin = std::getenv("ACCELBENCH_BIN");
  if (!bin) GTEST_SKIP() << "ACCELBENCH_BIN is not set (run through ctest)";
  TempDir dir("cli");
  write_scene(dir.path);
  const fs::path suite = dir.path / "s.json";
  std::ofstream(suite) << R"({"scenes": [{"scene": "anim.xml", "frames": 3, "strategies": ["sometimes"]}],
    "accelerators": ["bvh-sah"], "rays": [{"kind": "primary", "count": 8}]})";
  const fs::path err = dir.path / "err.txt";
  const int status = std::system(("'" + std::string(bin) + "' run '" + suite.string() + "' -o '" +
                                  (dir.path / "out").string() + "' 2> '" + err.string() + "'")
                                     .c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream in(err);
  std::stringstream text;
  text << in.rdbuf();
  const std::string e = text.str();
  EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << e;
  EXPECT_NE(e.find("scenes[0].strategies[0]: strategy 'sometimes'"), std::string::npos) << e;
}

TEST(DynamicSuite, AnimatedRunReportsEveryFrameVerified) {
  TempDir dir("run");
  write_scene(dir.path);
  const std::string text = R"({"repetitions": 1, "warmup": 0, "min_time": 0, "threads": [1, 2],
    "scenes": [{"scene": "anim.xml", "frames": 3, "strategies": ["rebuild", "refit", "adaptive", "top-level"]}],
    "accelerators": ["bvh-sah", {"name": "bvh-median", "params": {"width": 8}}, "grid", "embree"],
    "rays": [{"kind": "primary", "count": 300}], "verify": {"brute_rays": 0}})";
  const Suite suite = parse_suite(nlohmann::json::parse(text), "run.json", dir.path.string());
  RunOptions options;
  options.out_dir = (dir.path / "out").string();
  const nlohmann::json report = run_suite(suite, options);
  EXPECT_TRUE(report["verified"].get<bool>()) << report["failures"].dump();
  std::set<std::string> cases, labels;
  for (const auto& r : report["results"]) {
    ASSERT_TRUE(r.contains("frame"));
    EXPECT_TRUE(r["verified"].get<bool>());
    EXPECT_TRUE(r["update_seconds"].get<double>() > 0.0);
    EXPECT_TRUE(r.contains("frame_seconds"));
    labels.insert(r["config_label"].get<std::string>());
    EXPECT_TRUE(cases
                    .insert(r["config_label"].get<std::string>() + "/" + r["frame"].dump() + "/" +
                            r["threads"].dump())
                    .second);
    if (r["accelerator"] != "embree" && r["accelerator"] != "grid") {
      EXPECT_GT(r["sah_ratio_to_rebuild"].get<double>(), 0.0);
    }
    if (r["strategy"] == "rebuild" && r["accelerator"] != "embree" && r["accelerator"] != "grid") {
      EXPECT_EQ(r["sah_ratio_to_rebuild"].get<double>(), 1.0);
    }
  }
  for (const char* l : {"bvh-sah:rebuild", "bvh-sah:refit", "bvh-sah:adaptive", "bvh-sah:top-level",
                        "bvh-median{width=8}:refit", "grid:rebuild", "grid:top-level", "embree:rebuild"})
    EXPECT_TRUE(labels.count(l)) << l;
  EXPECT_FALSE(labels.count("grid:refit"));  // the grid does not refit
  EXPECT_FALSE(labels.count("embree:top-level"));
  ASSERT_TRUE(report.contains("frame_summary"));
  bool paying = false;
  for (const auto& s : report["frame_summary"]) {
    EXPECT_EQ(s["frames"].size(), 3u);
    EXPECT_TRUE(s["mean_frame_seconds"].is_number());
    if (s["strategy"] == "refit") paying = paying || s.contains("refit_stops_paying_frame");
  }
  EXPECT_TRUE(paying);
}

}  // namespace
}  // namespace ab
