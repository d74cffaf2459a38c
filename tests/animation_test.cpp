// Animated scenes: keyframe interpolation (exact at keys, midpoints, angles as angles, slerp, step), XML
// keyframes and their errors, deformers and frame files keeping triangle ids, the frame selector against
// the flattened frame, every structure byte-identical to brute on several frames at 1 and 2 threads, and
// the CLI's frame selector and animation rendering.
#include "tracer/animation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "accel/core/error.h"
#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "tests/cli_test_helpers.h"
#include "tests/scene_test_helpers.h"
#include "tracer/deform.h"
#include "tracer/sampling.h"
#include "tracer/scene.h"
#include "tracer/scene_accel.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

AnimatedElement keyed(AnimatedElement::Kind kind, std::vector<float> times,
                      std::vector<std::vector<float>> values) {
  AnimatedElement e;
  e.kind = kind;
  e.times = std::move(times);
  e.values = std::move(values);
  return e;
}

TEST(Animation, LinearKeysAreExactAtKeysAndMidwayBetween) {
  const AnimatedElement e = keyed(AnimatedElement::Kind::kTranslate, {0.0f, 2.0f, 3.0f},
                                  {{0.0f, 1.0f, 2.0f}, {4.0f, -1.0f, 2.0f}, {5.0f, 5.0f, 5.0f}});
  EXPECT_EQ(e.values_at(0.0f), (std::vector<float>{0.0f, 1.0f, 2.0f}));
  EXPECT_EQ(e.values_at(2.0f), (std::vector<float>{4.0f, -1.0f, 2.0f}));
  EXPECT_EQ(e.values_at(3.0f), (std::vector<float>{5.0f, 5.0f, 5.0f}));
  EXPECT_EQ(e.values_at(1.0f), (std::vector<float>{2.0f, 0.0f, 2.0f}));
  EXPECT_EQ(e.values_at(2.5f), (std::vector<float>{4.5f, 2.0f, 3.5f}));
  EXPECT_EQ(e.values_at(-1.0f), e.values_at(0.0f));  // clamped before the first key
  EXPECT_EQ(e.values_at(9.0f), e.values_at(3.0f));   // and after the last
  AnimatedElement step = e;
  step.interpolation = Interpolation::kStep;
  EXPECT_EQ(step.values_at(1.9f), e.values_at(0.0f));
  EXPECT_EQ(step.values_at(2.0f), e.values_at(2.0f));
}

TEST(Animation, AnglesInterpolateAsAngles) {
  // 0 to 360 degrees: the same matrix at both keys, a half turn midway (not the identity of a matrix lerp).
  AnimatedElement r = keyed(AnimatedElement::Kind::kRotate, {0.0f, 1.0f}, {{0.0f}, {360.0f}});
  r.axis = {0, 1, 0};
  const vec3 p = vec3(r.matrix_at(0.5f) * glm::vec4(1, 0, 0, 1));
  EXPECT_EQ(p, vec3(-1, 0, 0));
  const vec3 q = vec3(r.matrix_at(0.25f) * glm::vec4(1, 0, 0, 1));  // 90 degrees: exact
  EXPECT_EQ(q, vec3(0, 0, -1));
}

TEST(Animation, QuaternionsSlerpAlongTheShorterArc) {
  const float h = std::sqrt(0.5f);
  const glm::vec4 id(0, 0, 0, 1), quarter(0, 0, h, h);  // 90 degrees about z
  const glm::vec4 mid = slerp_quaternion(id, quarter, 0.5f);
  EXPECT_NEAR(mid.z, std::sin(0.3926991f), 1e-6f);  // 45 degrees about z
  EXPECT_NEAR(mid.w, std::cos(0.3926991f), 1e-6f);
  const glm::vec4 neg = slerp_quaternion(id, -quarter, 0.5f);  // -q is the same rotation
  EXPECT_NEAR(std::fabs(glm::dot(neg, mid)), 1.0f, 1e-6f);
  const vec3 p = vec3(quaternion_matrix(quarter) * glm::vec4(1, 0, 0, 1));
  EXPECT_NEAR(p.x, 0.0f, 1e-6f);
  EXPECT_NEAR(p.y, 1.0f, 1e-6f);
}

TEST(Animation, FrameFileNames) {
  std::string s;
  EXPECT_TRUE(frame_file_name("f_%04d.obj", 7, s));
  EXPECT_EQ(s, "f_0007.obj");
  EXPECT_TRUE(frame_file_name("f%d.png", 12, s));
  EXPECT_EQ(s, "f12.png");
  EXPECT_FALSE(frame_file_name("f.png", 1, s));
  EXPECT_FALSE(frame_file_name("f%d_%d.png", 1, s));
  EXPECT_FALSE(frame_file_name("f%s.png", 1, s));
  EXPECT_EQ(frame_time(0, 5), 0.0f);
  EXPECT_EQ(frame_time(4, 5), 1.0f);
  EXPECT_EQ(frame_time(2, 5), 0.5f);
  EXPECT_EQ(frame_time(0, 1), 0.0f);
  EXPECT_THROW(frame_time(5, 5), InputError);
  EXPECT_THROW(frame_time(0, 0), InputError);
}

const char* kQuad =
    "<mesh name='q'><vertices>0 0 0 1 0 0 0 1 0</vertices><triangles>0 1 2</triangles></mesh>\n";

std::string keyed_scene(const std::string& keys) {
  return std::string("<scene>\n") + kQuad + "<instance mesh='q'>\n" + keys + "</instance>\n</scene>\n";
}

Transform static_transform(const std::string& elements) {
  return parse_scene(keyed_scene(elements), "s.xml", ".").instances.at(0).transform;
}

TEST(Animation, XmlKeyframesEvaluateToTheStaticTransformAtEachKey) {
  const std::string k0 = "<translate>1 2 3</translate><rotate axis='0 1 1'>10</rotate><scale>1 2 3</scale>";
  const std::string k1 = "<translate>3 2 1</translate><rotate axis='0 1 1'>50</rotate><scale>2</scale>";
  const std::string k2 = "<translate>3 2 1</translate><rotate axis='0 1 1'>90</rotate><scale>3 2 1</scale>";
  const Scene s = parse_scene(keyed_scene("<keyframe time='2'>" + k0 + "</keyframe><keyframe time='4'>" + k1 +
                                          "</keyframe>\n<keyframe time='6'>" + k2 + "</keyframe>"),
                              "k.xml", ".");
  ASSERT_TRUE(s.animated());
  EXPECT_EQ(s.time_first, 2.0f);
  EXPECT_EQ(s.time_last, 6.0f);
  EXPECT_EQ(s.instances[0].transform.to_world, static_transform(k0).to_world);
  EXPECT_EQ(scene_at(s, 0.5f).instances[0].transform.to_world, static_transform(k1).to_world);
  EXPECT_EQ(scene_at(s, 1.0f).instances[0].transform.to_world, static_transform(k2).to_world);
  // Midway between keys 0 and 1 (time 3): each element's values halfway, then composed.
  const Transform mid = static_transform(
      "<translate>2 2 2</translate><rotate axis='0 1 1'>30</rotate><scale>1.5 2 2.5</scale>");
  EXPECT_EQ(scene_at(s, 0.25f).instances[0].transform.to_world, mid.to_world);
  EXPECT_EQ(scene_at(s, 0.25f).time, 0.25f);
}

TEST(Animation, NamedKeyedTransformsComposeWithInlineElements) {
  const Scene s = parse_scene(
      std::string("<scene>\n") + kQuad +
          "<transform name='m'><keyframe time='0'><translate>0 0 0</translate></keyframe>"
          "<keyframe time='1'><translate>4 0 0</translate></keyframe></transform>\n"
          "<instance mesh='q' transform='m'><scale>2</scale></instance>\n<instance mesh='q'/>\n</scene>",
      "n.xml", ".");
  const Scene half = scene_at(s, 0.5f);
  EXPECT_EQ(half.instances[0].transform.point(vec3(1, 0, 0)), vec3(4, 0, 0));  // scaled, then moved by 2
  EXPECT_EQ(half.instances[1].transform.to_world, glm::mat4(1.0f));
  EXPECT_EQ(half.world_bounds().hi.x, 4.0f);
}

TEST(Animation, BadKeyframesAreErrorsNamingTheLine) {
  test::expect_scene_error(keyed_scene("<keyframe time='0'><translate>0 0 0</translate></keyframe>\n"
                                       "<keyframe time='1'><scale>2</scale></keyframe>"),
                           5, "same elements in the same order");
  test::expect_scene_error(
      keyed_scene("<keyframe time='0'><translate>0 0 0</translate></keyframe>\n"
                  "<keyframe time='1'><translate>0 0 0</translate><scale>2</scale></keyframe>"),
      5, "same elements");
  test::expect_scene_error(keyed_scene("<keyframe time='0'><rotate axis='X'>0</rotate></keyframe>\n"
                                       "<keyframe time='1'><rotate axis='Y'>0</rotate></keyframe>"),
                           5, "same axis");
  test::expect_scene_error(keyed_scene("<keyframe time='1'><translate>0 0 0</translate></keyframe>\n"
                                       "<keyframe time='1'><translate>1 0 0</translate></keyframe>"),
                           5, "must increase");
  test::expect_scene_error(keyed_scene("<keyframe><translate>0 0 0</translate></keyframe>"), 4,
                           "needs attribute 'time'");
  test::expect_scene_error(keyed_scene("<keyframe time='x'><translate>0 0 0</translate></keyframe>"), 4,
                           "finite number");
  test::expect_scene_error(keyed_scene("<keyframe time='0'><scale>1</scale></keyframe>\n"
                                       "<keyframe time='1'><scale>0</scale></keyframe>"),
                           3, "singular");
  test::expect_scene_error(
      std::string("<scene>\n<mesh name='q' generator='tetra'>\n<deform type='melt'/></mesh>\n") +
          "<instance mesh='q'/></scene>",
      3, "unknown deformer type 'melt'");
  test::expect_scene_error(
      std::string("<scene>\n<mesh name='q' generator='tetra'>\n<deform type='wave' start='1' "
                  "end='1'/></mesh>\n<instance mesh='q'/></scene>"),
      3, "end > start");
  test::expect_scene_error(
      std::string("<scene>\n<mesh name='q' generator='tetra'>\n<deform type='twist'><distance>1"
                  "</distance></deform></mesh>\n<instance mesh='q'/></scene>"),
      3, "unknown element <distance>");
}

Mesh flake_mesh() {
  const Scene s = parse_scene(
      "<scene><mesh name='g' generator='sphereflake' triangles='400'/><instance mesh='g'/></scene>", "g.xml",
      ".");
  return *s.meshes[0].base;
}

TEST(Deform, EveryDeformerKeepsTheTriangleList) {
  const Mesh base = flake_mesh();
  ASSERT_GT(base.size(), 100u);
  for (Deformer::Kind kind : {Deformer::Kind::kWave, Deformer::Kind::kTwist, Deformer::Kind::kExplode}) {
    Deformer d;
    d.kind = kind;
    for (float t : {0.0f, 0.3f, 1.0f}) {
      const Mesh m = d.apply(base, t);
      ASSERT_EQ(m.size(), base.size());
      if (kind != Deformer::Kind::kExplode) {
        EXPECT_EQ(m.triangles, base.triangles);
      }
    }
    EXPECT_EQ(d.apply(base, 0.5f).vertices, d.apply(base, 0.5f).vertices);  // deterministic
  }
  Deformer twist;
  twist.kind = Deformer::Kind::kTwist;
  EXPECT_EQ(twist.apply(base, 0.0f).vertices, base.vertices);  // no twist at phase 0
  EXPECT_NE(twist.apply(base, 1.0f).vertices, base.vertices);
}

TEST(Deform, ExplodeMovesEachTriangleRigidlyAlongItsNormal) {
  const Mesh base = flake_mesh();
  Deformer d;
  d.kind = Deformer::Kind::kExplode;
  const Mesh still = d.apply(base, 0.0f), flown = d.apply(base, 1.0f);
  for (size_t i = 0; i < base.size(); ++i) {
    const Triangle a = base.triangle(i), b = still.triangle(i), c = flown.triangle(i);
    EXPECT_EQ(a.v0, b.v0);
    EXPECT_EQ(a.v2, b.v2);
    const vec3 off = c.v0 - a.v0, n = glm::normalize(glm::cross(a.v1 - a.v0, a.v2 - a.v0));
    EXPECT_NEAR(glm::length(c.v1 - a.v1 - off), 0.0f, 1e-4f);
    EXPECT_NEAR(glm::length(glm::cross(off, n)), 0.0f, 1e-3f * glm::length(off) + 1e-6f) << i;
    EXPECT_GT(glm::dot(off, n), 0.0f);
  }
}

/// A temporary folder removed at the end of the test.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name)
      : path(fs::temp_directory_path() / ("accelbench_anim_" + name + "_" + std::to_string(::getpid()))) {
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

TEST(Deform, FrameFilesSelectTheNearestFrameAndNeedOneTriangleCount) {
  TempDir dir("frames");
  for (int k = 0; k < 3; ++k)
    std::ofstream(dir.path / ("f_" + std::to_string(k) + ".obj"))
        << "v 0 0 " << k << "\nv 1 0 " << k << "\nv 0 1 " << k << "\nf 1 2 3\n";
  const std::string xml =
      "<scene><mesh name='m' frames='f_%d.obj' count='3' start='0' end='2'/><instance mesh='m'/></scene>";
  const Scene s = parse_scene(xml, "fr.xml", dir.path.string());
  ASSERT_TRUE(s.animated());
  EXPECT_EQ(s.meshes[0].mesh->vertices[0].z, 0.0f);
  EXPECT_EQ(scene_at(s, 0.5f).meshes[0].mesh->vertices[0].z, 1.0f);
  EXPECT_EQ(scene_at(s, 1.0f).meshes[0].mesh->vertices[0].z, 2.0f);
  EXPECT_EQ(scene_at(s, 0.7f).meshes[0].mesh->vertices[0].z, 1.0f);
  std::ofstream(dir.path / "f_1.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n";
  try {
    parse_scene(xml, "fr.xml", dir.path.string());
    ADD_FAILURE() << "a frame with another triangle count was accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("f_1.obj: frame has 2 triangles"), std::string::npos) << msg;
  }
  EXPECT_THROW(parse_scene("<scene><mesh name='m' frames='f_%d.obj' count='4'/><instance mesh='m'/></scene>",
                           "fr.xml", dir.path.string()),
               InputError);  // f_3.obj is missing
}

/// Four instances (two rigidly moving, one deforming, one exploding) over 2..3 time units.
std::string animated_scene_xml() {
  return "<scene>\n<camera><eye>0 3 12</eye><lookat>0 0 0</lookat></camera><ambient>0.3 0.3 0.3</ambient>\n"
         "<light type='point'><position>0 5 10</position><intensity>80 80 80</intensity></light>\n"
         "<mesh name='flake' generator='sphereflake' triangles='300' seed='3'/>\n"
         "<mesh name='wave' generator='tetra' triangles='256'><deform type='wave' start='2' end='3'>"
         "<amplitude>0.05</amplitude></deform></mesh>\n"
         "<mesh name='boom' generator='sphereflake' triangles='300'><deform type='explode' start='2' "
         "end='3'/></mesh>\n"
         "<instance mesh='flake'><keyframe time='2'><translate>-2 0 0</translate><rotate axis='Y'>0</rotate>"
         "</keyframe><keyframe time='3'><translate>2 1 0</translate><rotate "
         "axis='Y'>270</rotate></keyframe></instance>\n"
         "<instance mesh='flake'><translate>0 -1 0</translate><keyframe "
         "time='2.5'><scale>1</scale></keyframe>"
         "<keyframe time='3'><scale>0.5 2 1</scale></keyframe></instance>\n"
         "<instance mesh='wave'/>\n<instance mesh='boom'><translate>0 0 "
         "-1</translate></instance>\n</scene>\n";
}

std::vector<Ray> rays_into(const Scene& scene, size_t n) {
  const AABB b = scene.world_bounds();
  std::vector<Ray> rays;
  Rng rng(5, 1);
  auto point = [&] { return b.lo + vec3(rng.uniform(), rng.uniform(), rng.uniform()) * b.extent(); };
  for (size_t i = 0; i < n; ++i) {
    Ray r;
    r.org = i % 3 ? point() : b.center() + vec3(0, 0, 20);
    r.dir = point() - r.org;
    if (i % 13 == 0) r.dir = vec3(1, 0, 0);
    rays.push_back(r);
  }
  return rays;
}

TEST(AnimatedScene, EveryStructureMatchesBruteOnSeveralFrames) {
  const Scene scene = parse_scene(animated_scene_xml(), "anim.xml", ".");
  ASSERT_TRUE(scene.animated());
  for (uint64_t f : {0u, 2u, 4u}) {
    auto frame = std::make_shared<const Scene>(scene_at(scene, frame_time(f, 5)));
    const std::vector<Ray> rays = rays_into(*frame, 800);
    auto reference = make_scene_accelerator(frame, "brute", Params{});
    reference->build();
    std::vector<Hit> expected(rays.size());
    trace_closest(*reference, rays, expected, 1);
    size_t found = 0;
    for (const Hit& h : expected) found += h.found();
    ASSERT_GT(found, rays.size() / 5) << "frame " << f;
    for (const AcceleratorInfo& info : accelerators()) {
      if (!info.make_for_instances || info.name.rfind("test-", 0) == 0 || info.name == "embree") continue;
      auto accel = make_scene_accelerator(frame, info.name, Params{});
      accel->build();
      for (int threads : {1, 2}) {
        std::vector<Hit> hits(rays.size());
        trace_closest(*accel, rays, hits, threads);
        EXPECT_EQ(std::memcmp(hits.data(), expected.data(), hits.size() * sizeof(Hit)), 0)
            << info.name << ", frame " << f << ", " << threads << " threads";
      }
    }
  }
}

TEST(AnimatedScene, FramesMoveAndDeformTheGeometry) {
  const Scene scene = parse_scene(animated_scene_xml(), "anim.xml", ".");
  EXPECT_EQ(scene.time_first, 2.0f);
  EXPECT_EQ(scene.time_last, 3.0f);
  const Scene a = scene_at(scene, 0.0f), b = scene_at(scene, 1.0f);
  EXPECT_EQ(a.instances[0].transform.point(vec3(0)), vec3(-2, 0, 0));
  EXPECT_EQ(b.instances[0].transform.point(vec3(0)), vec3(2, 1, 0));
  EXPECT_EQ(scene_at(scene, 0.25f).instances[1].transform.to_world,
            a.instances[1].transform.to_world);  // before its first key
  EXPECT_NE(a.meshes[1].mesh->vertices, b.meshes[1].mesh->vertices);
  EXPECT_EQ(a.meshes[0].mesh, b.meshes[0].mesh);  // static meshes are shared, not copied
  EXPECT_EQ(a.triangle_count(), b.triangle_count());
  EXPECT_GT(b.world_bounds().area(), a.world_bounds().area());  // the explosion grows the box
}

TEST(AnimatedScene, AFrameTracedAsASceneMatchesItsFlattenedMesh) {
  // Untransformed instances (a deforming and an exploding mesh): object space is world space, so the
  // instanced hits equal the flattened mesh's bit for bit, ids mapped.
  const Scene scene = parse_scene(
      "<scene><mesh name='w' generator='sphereflake' triangles='300'><deform type='twist'/></mesh>"
      "<mesh name='e' generator='tetra' triangles='200'><deform type='explode'/></mesh>"
      "<instance mesh='w'/><instance mesh='e'/></scene>",
      "flat.xml", ".");
  const auto frame = std::make_shared<const Scene>(scene_at(scene, 0.6f));
  const Mesh flat = flatten_scene(*frame);
  const uint32_t first = uint32_t(frame->meshes[0].mesh->size());
  auto world = make_accelerator("brute", std::make_shared<TrianglePrims>(std::make_shared<Mesh>(flat)), {});
  world->build();
  auto inst = make_scene_accelerator(frame, "bvh-sah", Params{});
  inst->build();
  const std::vector<Ray> rays = rays_into(*frame, 1000);
  std::vector<Hit> a(rays.size()), b(rays.size());
  world->intersect(rays, a);
  inst->intersect(rays, b);
  size_t hits = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(a[i].found(), b[i].found()) << i;
    if (!a[i].found()) continue;
    ++hits;
    EXPECT_EQ(a[i].t, b[i].t) << i;
    EXPECT_EQ(a[i].prim, b[i].prim + (b[i].inst ? first : 0u)) << i;
  }
  EXPECT_GT(hits, rays.size() / 5);
}

TEST(AnimatedScene, ShippedAnimationsAreIdenticalToBruteOnSomeFrames) {
  const fs::path dir = fs::path(ACCELBENCH_SOURCE_DIR) / "datasets" / "scenes";
  for (const char* name : {"orbit.xml", "wave.xml", "explode.xml"}) {
    const Scene scene = load_scene((dir / name).string());
    ASSERT_TRUE(scene.animated()) << name;
    for (uint64_t f : {0u, 30u, 47u}) {
      auto frame = std::make_shared<const Scene>(scene_at(scene, frame_time(f, 48)));
      const std::vector<Ray> rays = rays_into(*frame, 400);
      auto brute = make_scene_accelerator(frame, "brute", Params{});
      brute->build();
      std::vector<Hit> expected(rays.size());
      trace_closest(*brute, rays, expected, 1);
      for (const char* accel : {"bvh-sah", "kdtree-sah", "grid"}) {
        auto a = make_scene_accelerator(frame, accel, Params{});
        a->build();
        std::vector<Hit> hits(rays.size());
        trace_closest(*a, rays, hits, 2);
        EXPECT_EQ(std::memcmp(hits.data(), expected.data(), hits.size() * sizeof(Hit)), 0)
            << name << " frame " << f << " " << accel;
      }
    }
  }
}

bool have_cli() {
  return fs::exists(test::accelbench_exe());
}

TEST(AnimatedSceneCli, TheFrameSelectorGivesTheFlattenedFramesHits) {
  if (!have_cli()) GTEST_SKIP() << "accelbench binary not found";
  TempDir dir("cli_frame");
  const std::string scene = (dir.path / "s.xml").string(), d = dir.path.string() + "/";
  std::ofstream(scene)
      << "<scene><camera><eye>0 0 6</eye><lookat>0 0 0</lookat></camera>"
         "<mesh name='w' generator='sphereflake' triangles='300'><deform type='twist'/></mesh>"
         "<mesh name='e' generator='tetra' triangles='200'><deform type='explode'/></mesh>"
         "<instance mesh='w'/><instance mesh='e'/></scene>\n";
  const std::string frame = " --frame 3 --frames 5";
  ASSERT_EQ(test::run_accelbench(
                "rays --scene " + scene + frame + " --kind primary --count 2000 -o " + d + "r.rays", dir.path)
                .first,
            0);
  ASSERT_EQ(test::run_accelbench("trace --scene " + scene + frame + " --accel bvh-sah --rays " + d +
                                     "r.rays -o " + d + "s.hits",
                                 dir.path)
                .first,
            0);
  ASSERT_EQ(test::run_accelbench("flatten --scene " + scene + frame + " -o " + d + "f.obj", dir.path).first,
            0);
  ASSERT_EQ(
      test::run_accelbench(
          "trace --mesh " + d + "f.obj --accel grid --rays " + d + "r.rays -o " + d + "m.hits", dir.path)
          .first,
      0);
  ASSERT_EQ(test::run_accelbench("trace --scene " + scene + " --time 0.75 --accel kdtree-sah --rays " + d +
                                     "r.rays -o " + d + "t.hits",
                                 dir.path)
                .first,
            0);
  EXPECT_EQ(test::read_text(d + "s.hits"), test::read_text(d + "t.hits"));  // frame 3 of 5 is time 0.75
  ASSERT_EQ(
      test::run_accelbench(
          "trace --scene " + scene + " --accel bvh-sah --rays " + d + "r.rays -o " + d + "0.hits", dir.path)
          .first,
      0);
  EXPECT_NE(test::read_text(d + "s.hits"), test::read_text(d + "0.hits"));  // and differs from frame 0
  const Scene parsed = load_scene(scene);
  const uint32_t first = uint32_t(parsed.meshes[0].mesh->size());
  const std::string sh = test::read_text(d + "s.hits"), mh = test::read_text(d + "m.hits");
  ASSERT_EQ(sh.size(), mh.size());
  size_t found = 0;
  for (size_t off = 16; off + 20 <= sh.size(); off += 20) {
    Hit a, b;
    std::memcpy(&a, sh.data() + off, 20);
    std::memcpy(&b, mh.data() + off, 20);
    ASSERT_EQ(a.t, b.t) << off;
    if (!a.found()) continue;
    ++found;
    EXPECT_EQ(b.prim, a.prim + (a.inst ? first : 0u));
    EXPECT_EQ(a.u, b.u);
  }
  EXPECT_GT(found, 200u);
}

TEST(AnimatedSceneCli, BadFramesAndBadAnimationsExitTwoWithOneLine) {
  if (!have_cli()) GTEST_SKIP() << "accelbench binary not found";
  TempDir dir("cli_bad");
  const std::string scene = (dir.path / "a.xml").string(), bad = (dir.path / "bad.xml").string();
  const std::string d = dir.path.string() + "/";
  std::ofstream(scene) << animated_scene_xml();
  std::ofstream(bad) << keyed_scene(
      "<keyframe time='0'><translate>0 0 0</translate></keyframe>\n"
      "<keyframe time='1'><scale>2</scale></keyframe>");
  ASSERT_EQ(test::run_accelbench("rays --scene " + scene + " --kind primary --count 50 -o " + d + "r.rays",
                                 dir.path)
                .first,
            0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"flatten --scene " + scene + " --frame 5 --frames 5 -o " + d + "o.obj", "out of range"},
      {"flatten --scene " + scene + " --frame 1 -o " + d + "o.obj", "--frame F needs --frames N"},
      {"rays --scene " + scene + " --frames 2-3 --frame 0 --kind primary --count 5 -o " + d + "o.rays",
       "range is for render"},
      {"trace --scene " + scene + " --time 1.5 --accel brute --rays " + d + "r.rays -o " + d + "o.hits",
       "--time"},
      {"trace --scene " + bad + " --accel brute --rays " + d + "r.rays -o " + d + "o.hits", "bad.xml:5:"},
      {"verify --scene " + scene + " --frames x --frame 0 --count 10", "--frames x"},
      {"render --scene " + scene + " --frames 0-1 -o " + d + "o.png", "pattern"},
      {"render --scene " + scene + " --frames 29-30 -o " + d + "o_%d.png", "out of range"},
  };
  for (const auto& [cmd, words] : cases) {
    const auto [code, err] = test::run_accelbench(cmd, dir.path);
    EXPECT_EQ(code, 2) << cmd << ": " << err;
    EXPECT_NE(err.find(words), std::string::npos) << cmd << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  }
  for (const char* f : {"o.obj", "o.rays", "o.hits", "o.png", "o_29.png"})
    EXPECT_FALSE(fs::exists(dir.path / f)) << f;
}

TEST(AnimatedSceneCli, RenderFramesWritesOnePngPerFrameOnAnyThreadCount) {
  if (!have_cli()) GTEST_SKIP() << "accelbench binary not found";
  TempDir dir("cli_render");
  const std::string scene = (dir.path / "a.xml").string(), d = dir.path.string() + "/";
  std::ofstream(scene) << animated_scene_xml();
  const std::string common = "render --scene " + scene + " --width 24 --height 16 --spp 1 --frames 1-2 ";
  ASSERT_EQ(test::run_accelbench(common + "--threads 1 -o " + d + "one_%02d.png", dir.path).first, 0);
  ASSERT_EQ(test::run_accelbench(common + "--threads 2 -o " + d + "two_%02d.png", dir.path).first, 0);
  EXPECT_FALSE(fs::exists(dir.path / "one_00.png"));
  for (const char* f : {"01", "02"}) {
    ASSERT_TRUE(fs::exists(dir.path / ("one_" + std::string(f) + ".png"))) << f;
    EXPECT_EQ(test::read_text(d + "one_" + f + ".png"), test::read_text(d + "two_" + f + ".png")) << f;
  }
  EXPECT_NE(test::read_text(d + "one_01.png"), test::read_text(d + "one_02.png"));
  ASSERT_EQ(
      test::run_accelbench("render --scene " + scene +
                               " --width 24 --height 16 --spp 1 --frame 2 --frames 30 -o " + d + "single.png",
                           dir.path)
          .first,
      0);
  EXPECT_EQ(test::read_text(d + "single.png"), test::read_text(d + "one_02.png"));
}

}  // namespace
}  // namespace ab
