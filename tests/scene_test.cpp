// Scenes: parsing, errors with line numbers, instancing (each base mesh built once), instanced hits
// against the flattened mesh, byte-identical hits across every structure at both levels, Embree's
// instances, flatten and the CLI's answers to bad scenes.
#include "tracer/scene.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "accel/core/error.h"
#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "accel/reference/embree_scene.h"
#include "tests/cli_test_helpers.h"
#include "tests/scene_test_helpers.h"
#include "tracer/sampling.h"
#include "tracer/scene_accel.h"
#include "tracer/workload.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

/// A scene of `count` instances of two generated meshes and an inline quad, under rotations about
/// arbitrary axes and non-uniform scales, on a jittered lattice (instances overlap their neighbours).
std::string instanced_scene_xml(int count) {
  std::ostringstream os;
  os << "<scene>\n<camera><eye>0 8 30</eye><lookat>0 0 0</lookat></camera>\n"
     << "<light type='area'><corner>-5 20 -5</corner><edge1>10 0 0</edge1><edge2>0 0 -10</edge2>"
     << "<radiance>1 1 1</radiance></light>\n"
     << "<material name='g' type='glossy'><roughness>0.2</roughness></material>\n"
     << "<mesh name='flake' generator='sphereflake' triangles='300' seed='3'/>\n"
     << "<mesh name='tetra' generator='tetra' triangles='256' seed='1'/>\n"
     << "<mesh name='quad'><vertices>-1 0 -1 1 0 -1 1 0 1 -1 0 1</vertices><triangles>0 2 1 0 3 "
        "2</triangles></mesh>\n";
  Rng rng(7, 0);
  for (int i = 0; i < count; ++i) {
    const char* mesh = i % 7 == 6 ? "quad" : (i % 2 ? "tetra" : "flake");
    os << "<instance mesh='" << mesh << "'" << (i % 3 == 0 ? " material='g'" : "") << ">"
       << "<translate>" << (i % 15) * 1.6f - 11.0f + rng.uniform() << " " << (i / 15 % 4) * 1.5f - 3.0f << " "
       << (i / 60) * 1.7f - 4.0f + rng.uniform() << "</translate>"
       << "<rotate axis='" << rng.uniform() - 0.5f << " " << rng.uniform() << " " << rng.uniform() - 0.5f
       << "'>" << rng.uniform() * 360.0f << "</rotate>"
       << "<scale>" << 0.4f + rng.uniform() << " " << 0.3f + 0.5f * rng.uniform() << " "
       << 0.5f + rng.uniform() << "</scale></instance>\n";
  }
  os << "</scene>\n";
  return os.str();
}

std::shared_ptr<const Scene> instanced_scene(int count) {
  return std::make_shared<const Scene>(parse_scene(instanced_scene_xml(count), "instanced.xml", "."));
}

/// Rays aimed at random points of the scene's bounds from outside and inside, some with finite tmax
/// and axis-aligned directions.
std::vector<Ray> scene_rays(const Scene& scene, size_t n) {
  const AABB b = scene.world_bounds();
  std::vector<Ray> rays;
  Rng rng(11, 3);
  auto point = [&] { return b.lo + vec3(rng.uniform(), rng.uniform(), rng.uniform()) * b.extent(); };
  for (size_t i = 0; i < n; ++i) {
    Ray r;
    r.org = i % 2 ? point() : b.center() + 2.0f * (point() - b.center()) + vec3(0, 0, 30);
    r.dir = point() - r.org;
    if (i % 11 == 0) r.dir = vec3(0, 0, i % 22 ? 1.0f : -1.0f);
    if (i % 5 == 0) r.tmax = 0.5f;
    rays.push_back(r);
  }
  return rays;
}

const char* kQuad =
    "<mesh name='q'><vertices>0 0 0 1 0 0 0 1 0</vertices><triangles>0 1 2</triangles></mesh>\n";

TEST(Scene, ParsesEverything) {
  const auto scene = instanced_scene(30);  // keep the owner alive: a reference into a temporary dangles
  const Scene& s = *scene;
  EXPECT_EQ(s.instances.size(), 30u);
  EXPECT_EQ(s.meshes.size(), 3u);
  EXPECT_EQ(s.meshes[2].mesh->size(), 2u);
  EXPECT_EQ(s.materials.size(), 2u);  // default + g
  EXPECT_EQ(s.materials[1].type, Material::Type::kGlossy);
  EXPECT_FLOAT_EQ(s.materials[1].roughness, 0.2f);
  EXPECT_EQ(s.instances[0].material, 1u);
  EXPECT_EQ(s.instances[1].material, 0u);
  EXPECT_EQ(s.area_lights.size(), 1u);
  EXPECT_FLOAT_EQ(s.camera.eye.z, 30.0f);
  uint64_t tris = 0;
  for (const auto& i : s.instances) tris += s.meshes[i.mesh].mesh->size();
  EXPECT_EQ(s.triangle_count(), tris);
}

TEST(Scene, ErrorsNameTheFileAndLine) {
  test::expect_scene_error("<scene>\n<instance mesh='q'/>\n<oops>\n</scene>", 4, "malformed XML");
  test::expect_scene_error(std::string("<scene>\n") + kQuad + "<instance mesh='nope'/>\n</scene>", 3,
                           "unknown mesh 'nope'");
  test::expect_scene_error(std::string("<scene>\n") + kQuad + "\n<instance mesh='q' material='m'/></scene>",
                           4, "unknown material 'm'");
  test::expect_scene_error(std::string("<scene>\n") + kQuad + "<instance mesh='q' transform='t'/></scene>", 3,
                           "unknown transform 't'");
  test::expect_scene_error(std::string("<scene>\n") + kQuad +
                               "<instance mesh='q'>\n<translate>1 2 x</translate></instance></scene>",
                           4, "bad number 'x'");
  test::expect_scene_error(
      std::string("<scene>\n") + kQuad + "<instance mesh='q'>\n<translate>1 2</translate></instance></scene>",
      4, "needs 3 numbers");
  test::expect_scene_error(
      std::string("<scene>\n") + kQuad + "<instance mesh='q'>\n<scale>1 nan 1</scale></instance></scene>", 4,
      "bad number 'nan'");
  test::expect_scene_error(
      std::string("<scene>\n") + kQuad + "<instance mesh='q'/>\n<camera><fov>500</fov></camera></scene>", 4,
      "fov");
  test::expect_scene_error(std::string("<scene>\n") + kQuad + "<instance mesh='q'/>\n\n<lamp/></scene>", 5,
                           "unknown element <lamp>");
  test::expect_scene_error(
      std::string("<scene>\n") + kQuad + "<instance mesh='q'/>\n<material name='m' type='velvet'/></scene>",
      4, "velvet");
  test::expect_scene_error(
      "<scene>\n<mesh name='q'><vertices>0 0 0</vertices>\n<triangles>0 1 2</triangles></mesh></scene>", 3,
      "out of range");
  test::expect_scene_error("<scene>\n<mesh name='g' generator='no-such-generator'/>\n</scene>", 2,
                           "no-such-generator");
  test::expect_scene_error("<scene>\n<mesh name='f' file='missing.obj'/>\n</scene>", 2, "missing.obj");
  test::expect_scene_error(std::string("<scene>\n") + kQuad + kQuad + "</scene>", 3, "declared twice");
  test::expect_scene_error(std::string("<scene>\n") + kQuad + "</scene>", 1, "no <instance>");
  test::expect_scene_error(std::string("<scene>\n") + kQuad +
                               "<instance mesh='q'>\n<rotate axis='W'>3</rotate></instance></scene>",
                           4, "axis");
}

TEST(Scene, EachBaseMeshIsLoadedAndBuiltOnce) {
  auto scene = instanced_scene(40);
  EXPECT_EQ(scene->meshes.size(), 3u);
  SceneAccelerator accel(scene, "brute", "brute", Params{});
  accel.build();
  EXPECT_EQ(accel.stats().extra["base_meshes"], 3);
  EXPECT_EQ(accel.stats().extra["bottoms"].size(), 3u);
  EXPECT_EQ(accel.stats().primitives, 300u + 256u + 2u);  // each base mesh once, not per instance
  EXPECT_EQ(accel.top().stats().primitives, 40u);
}

TEST(Scene, InstancedHitsMatchTheFlattenedMesh) {
  auto scene = instanced_scene(300);
  const Mesh flat = flatten_scene(*scene);
  ASSERT_EQ(flat.size(), scene->triangle_count());
  std::vector<uint32_t> first(scene->instances.size() + 1, 0);
  for (size_t i = 0; i < scene->instances.size(); ++i)
    first[i + 1] = first[i] + uint32_t(scene->meshes[scene->instances[i].mesh].mesh->size());
  const std::string fast = "bvh-sah";
  const bool have_bvh = [&] {
    for (const auto& a : accelerators())
      if (a.name == fast) return true;
    return false;
  }();
  auto world = make_accelerator(have_bvh ? fast : "brute",
                                std::make_shared<TrianglePrims>(std::make_shared<Mesh>(flat)), {});
  world->build();
  auto inst = make_scene_accelerator(scene, have_bvh ? fast : "brute", Params{});
  inst->build();
  const std::vector<Ray> rays = scene_rays(*scene, 3000);
  std::vector<Hit> a(rays.size()), b(rays.size());
  world->intersect(rays, a);
  inst->intersect(rays, b);
  size_t hits = 0, same = 0, found_differs = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (a[i].found() != b[i].found()) {
      ++found_differs;
      continue;
    }
    if (!a[i].found()) continue;
    ++hits;
    EXPECT_NEAR(a[i].t, b[i].t, 1e-4f * std::max(1.0f, a[i].t)) << "ray " << i;
    same += a[i].prim == first[b[i].inst] + b[i].prim;
  }
  EXPECT_GT(hits, rays.size() / 4);
  EXPECT_LE(found_differs, rays.size() / 500);  // grazing edges only
  EXPECT_GE(same, hits - hits / 200);           // ties on shared edges and overlaps only
}

TEST(Scene, EveryStructureGivesByteIdenticalHitsAtBothLevels) {
  auto scene = instanced_scene(120);
  const std::vector<Ray> rays = scene_rays(*scene, 1500);
  auto reference = make_scene_accelerator(scene, "brute", Params{});
  reference->build();
  std::vector<Hit> expected(rays.size());
  trace_closest(*reference, rays, expected, 1);
  std::vector<uint8_t> blocked(rays.size());
  reference->occluded(rays, blocked);
  size_t found = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    found += expected[i].found();
    EXPECT_EQ(blocked[i], expected[i].found()) << "ray " << i;
  }
  ASSERT_GT(found, rays.size() / 4);
  int tested = 0;
  for (const AcceleratorInfo& info : accelerators()) {
    if (!info.make_for_instances || info.name.rfind("test-", 0) == 0) continue;
    for (const auto& [top, bottom] :
         {std::pair{info.name, info.name}, std::pair{info.name, std::string("brute")},
          std::pair{std::string("brute"), info.name}}) {
      auto accel = make_scene_accelerator(scene, top, Params{}, top, bottom);
      accel->build();
      for (int threads : {1, 2}) {
        std::vector<Hit> hits(rays.size());
        trace_closest(*accel, rays, hits, threads);
        EXPECT_EQ(std::memcmp(hits.data(), expected.data(), hits.size() * sizeof(Hit)), 0)
            << "top " << top << ", bottom " << bottom << ", " << threads << " threads";
      }
      std::vector<uint8_t> occ(rays.size());
      accel->occluded(rays, occ);
      EXPECT_EQ(occ, blocked) << "occluded: top " << top << ", bottom " << bottom;
      ++tested;
    }
  }
  EXPECT_GE(tested, 3);
}

TEST(Scene, EmbreeInstancesAgreeWithBrute) {
  auto scene = instanced_scene(120);
  const std::vector<Ray> rays = scene_rays(*scene, 2000);
  auto reference = make_scene_accelerator(scene, "brute", Params{});
  auto embree = make_scene_accelerator(scene, "embree", Params{});
  EXPECT_EQ(embree->name(), "embree");
  reference->build();
  embree->build();
  std::vector<Hit> a(rays.size()), b(rays.size());
  reference->intersect(rays, a);
  embree->intersect(rays, b);
  size_t agree = 0;
  for (size_t i = 0; i < rays.size(); ++i)
    agree += a[i].inst == b[i].inst && a[i].prim == b[i].prim &&
             (!a[i].found() || std::fabs(a[i].t - b[i].t) <= 1e-4f * std::max(1.0f, std::fabs(a[i].t)));
  EXPECT_GE(agree, rays.size() - rays.size() / 200);
  std::vector<uint8_t> oa(rays.size()), ob(rays.size());
  reference->occluded(rays, oa);
  embree->occluded(rays, ob);
  size_t occ_agree = 0;
  for (size_t i = 0; i < rays.size(); ++i) occ_agree += oa[i] == ob[i];
  EXPECT_GE(occ_agree, rays.size() - rays.size() / 200);
}

TEST(Scene, LevelParametersAreRoutedAndChecked) {
  Params p;
  p.add("top.a=1");
  p.add("bottom.b=2");
  p.add("c=3");
  const Params top = level_params(p, "top", "bottom");
  const Params bottom = level_params(p, "bottom", "top");
  EXPECT_EQ(top.values(), (std::map<std::string, std::string>{{"a", "1"}, {"c", "3"}}));
  EXPECT_EQ(bottom.values(), (std::map<std::string, std::string>{{"b", "2"}, {"c", "3"}}));
  auto scene = instanced_scene(3);
  Params bad;
  bad.add("no-such-param=1");
  EXPECT_THROW(make_scene_accelerator(scene, "brute", bad), ParamError);
  EXPECT_THROW(make_scene_accelerator(scene, "no-such-structure", Params{}), InputError);
}

TEST(Scene, WorkloadsAreExactAndDeterministic) {
  auto scene = instanced_scene(60);
  const bool have_bvh = [&] {
    for (const auto& a : accelerators())
      if (a.name == "bvh-sah") return true;
    return false;
  }();
  auto accel = make_scene_accelerator(scene, have_bvh ? "bvh-sah" : "brute", Params{});
  accel->build();
  const TraceFn trace = [&](std::span<const Ray> r, std::span<Hit> h) { accel->intersect(r, h); };
  for (const auto& kind : scene_ray_kinds()) {
    const auto a = make_scene_rays(*scene, trace, kind.name, 777, 5);
    const auto b = make_scene_rays(*scene, trace, kind.name, 777, 5);
    ASSERT_EQ(a.size(), 777u) << kind.name;
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Ray)), 0) << kind.name;
    const auto c = make_scene_rays(*scene, trace, kind.name, 777, 6);
    EXPECT_NE(std::memcmp(a.data(), c.data(), a.size() * sizeof(Ray)), 0) << kind.name;
  }
  for (const Ray& r : make_scene_rays(*scene, trace, "primary", 100, 1)) EXPECT_EQ(r.org, scene->camera.eye);
  // Shadow rays end (at t = 1) on the area light.
  const AreaLight& l = scene->area_lights[0];
  for (const Ray& r : make_scene_rays(*scene, trace, "shadow", 200, 1)) {
    const vec3 end = r.org + r.dir;
    EXPECT_NEAR(end.y, l.corner.y, 1e-4f);
    EXPECT_LT(r.tmax, 1.0f);
  }
  EXPECT_THROW(make_scene_rays(*scene, trace, "sideways", 10, 1), InputError);
}

TEST(Scene, FlattenKeepsDocumentAndBaseMeshOrder) {
  auto scene = instanced_scene(5);
  const Mesh flat = flatten_scene(*scene);
  size_t k = 0;
  for (const SceneInstance& inst : scene->instances) {
    const Mesh& m = *scene->meshes[inst.mesh].mesh;
    for (size_t i = 0; i < m.size(); ++i, ++k) {
      const Triangle a = m.triangle(i), b = flat.triangle(k);
      EXPECT_EQ(b.v0, inst.transform.point(a.v0));
      EXPECT_EQ(b.v2, inst.transform.point(a.v2));
    }
  }
  EXPECT_EQ(k, flat.size());
}

TEST(Scene, ExampleScenesLoad) {
  const fs::path dir = fs::path(ACCELBENCH_SOURCE_DIR) / "datasets" / "scenes";
  const Scene forest = load_scene((dir / "forest.xml").string());
  EXPECT_EQ(forest.instances.size(), 401u);
  EXPECT_EQ(forest.meshes.size(), 4u);
  const Scene showcase = load_scene((dir / "showcase.xml").string());
  EXPECT_EQ(showcase.instances.size(), 5u);
  EXPECT_GT(showcase.camera.aperture, 0.0f);
}

TEST(Scene, RealMeshSceneLoadsWhereTheMeshesAre) {
  const fs::path dir = fs::path(ACCELBENCH_SOURCE_DIR) / "datasets" / "scenes";
  if (!fs::exists(dir / "../../../shared/meshes/stanford-bunny.obj"))
    GTEST_SKIP() << "../shared/meshes is absent (a user's clone)";
  auto scene = std::make_shared<const Scene>(load_scene((dir / "real_meshes.xml").string()));
  EXPECT_EQ(scene->meshes[0].mesh->size(), 69451u);
  EXPECT_EQ(scene->meshes[1].mesh->size(), 6320u);
  // The two bunnies share one base mesh; byte-identical hits through the real meshes too (two
  // structures with fast builds; every structure meets every real mesh in the conformance test).
  auto a = make_scene_accelerator(scene, "brute", Params{});
  a->build();
  const std::vector<Ray> rays = scene_rays(*scene, 300);
  std::vector<Hit> expected(rays.size());
  a->intersect(rays, expected);
  for (const AcceleratorInfo& info : accelerators()) {
    if (info.name != "bvh-sah" && info.name != "grid") continue;
    auto b = make_scene_accelerator(scene, info.name, Params{});
    b->build();
    std::vector<Hit> hits(rays.size());
    b->intersect(rays, hits);
    EXPECT_EQ(std::memcmp(hits.data(), expected.data(), hits.size() * sizeof(Hit)), 0) << info.name;
  }
}

TEST(Scene, CliRejectsBadScenesWithOneLine) {
  if (!fs::exists(test::accelbench_exe())) GTEST_SKIP() << "accelbench binary not found";
  const fs::path dir = fs::temp_directory_path() / ("accelbench_scene_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path bad = dir / "bad.xml";
  std::ofstream(bad) << "<scene>\n"
                     << kQuad << "<instance mesh='q'>\n<scale>1 x 1</scale></instance>\n</scene>\n";
  for (const std::string& cmd :
       {"render --scene " + bad.string() + " -o " + (dir / "o.png").string(),
        "flatten --scene " + bad.string() + " -o " + (dir / "o.obj").string(),
        "rays --scene " + bad.string() + " --kind primary --count 5 -o " + (dir / "o.rays").string()}) {
    const auto [code, err] = test::run_accelbench(cmd, dir);
    EXPECT_EQ(code, 2) << cmd << ": " << err;
    EXPECT_NE(err.find("bad.xml:4:"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  EXPECT_FALSE(fs::exists(dir / "o.png"));
  EXPECT_FALSE(fs::exists(dir / "o.obj"));
  fs::remove_all(dir);
}

TEST(Scene, CliFlattenAndRaysWork) {
  if (!fs::exists(test::accelbench_exe())) GTEST_SKIP() << "accelbench binary not found";
  const fs::path dir = fs::temp_directory_path() / ("accelbench_scene_ok_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path scene = dir / "s.xml";
  std::ofstream(scene) << instanced_scene_xml(10);
  EXPECT_EQ(test::run_accelbench("flatten --scene " + scene.string() + " -o " + (dir / "f.obj").string(), dir)
                .first,
            0);
  EXPECT_TRUE(fs::exists(dir / "f.obj"));
  for (const char* kind : {"primary", "dof", "shadow", "glossy", "diffuse"}) {
    const fs::path out = dir / (std::string(kind) + ".rays");
    EXPECT_EQ(
        test::run_accelbench(
            "rays --scene " + scene.string() + " --kind " + kind + " --count 100 -o " + out.string(), dir)
            .first,
        0);
    EXPECT_EQ(fs::file_size(out), 16u + 100u * 32u) << kind;
  }
  fs::remove_all(dir);
}

TEST(Scene, CliRendersTheSamePngForAnyThreadCount) {
  if (!fs::exists(test::accelbench_exe())) GTEST_SKIP() << "accelbench binary not found";
  const fs::path dir = fs::temp_directory_path() / ("accelbench_scene_png_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path scene = dir / "s.xml";
  std::ofstream(scene) << instanced_scene_xml(20);
  const std::string base =
      "render --scene " + scene.string() + " --width 40 --height 30 --spp 4 --accel brute";
  EXPECT_EQ(test::run_accelbench(base + " --threads 1 -o " + (dir / "a.png").string(), dir).first, 0);
  EXPECT_EQ(test::run_accelbench(base + " --threads 2 -o " + (dir / "b.png").string(), dir).first, 0);
  EXPECT_EQ(test::run_accelbench(base + " --heatmap -o " + (dir / "h.png").string(), dir).first, 0);
  EXPECT_FALSE(test::read_text(dir / "a.png").empty());
  EXPECT_EQ(test::read_text(dir / "a.png"), test::read_text(dir / "b.png"));
  EXPECT_TRUE(fs::exists(dir / "h.png"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ab
