// glTF 2.0 scenes: a round trip (a keyframed XML scene written with tinygltf and read back: the same
// triangles in the same order at every time), node hierarchies, STEP and LINEAR channels, triangle strips,
// the CLI on .gltf and .glb, and malformed files answered with one line naming the file.
#include "tracer/gltf.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "accel/core/error.h"
#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "tests/cli_test_helpers.h"
#include "tracer/scene.h"
#include "tracer/scene_accel.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name)
      : path(fs::temp_directory_path() / ("accelbench_gltf_" + name + "_" + std::to_string(::getpid()))) {
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string operator/(const std::string& f) const { return (path / f).string(); }
};

const char* kRigid =
    "<scene>\n"
    "<mesh name='flake' generator='sphereflake' triangles='300' seed='2'/>\n"
    "<mesh name='quad'><vertices>-1 0 -1 1 0 -1 1 0 1 -1 0 1</vertices><triangles>0 2 1 0 3 "
    "2</triangles></mesh>\n"
    "<instance mesh='quad'><scale>4</scale></instance>\n"
    "<instance mesh='flake'><translate>0 1 0</translate>"
    "<keyframe time='0'><translate>-2 0 0</translate><rotate axis='0 1 "
    "1'>0</rotate><scale>1</scale></keyframe>"
    "<keyframe time='1.5'><translate>2 0 0</translate><rotate axis='0 1 1'>300</rotate><scale>0.5 1 "
    "2</scale></keyframe>"
    "<keyframe time='3'><translate>2 2 0</translate><rotate axis='0 1 "
    "1'>330</rotate><scale>1</scale></keyframe>"
    "</instance>\n"
    "<instance mesh='flake'><rotate axis='X'>90</rotate><translate>0 0 3</translate></instance>\n"
    "</scene>\n";

void expect_near_meshes(const Mesh& a, const Mesh& b, float tol) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    const Triangle x = a.triangle(i), y = b.triangle(i);
    ASSERT_NEAR(glm::length(x.v0 - y.v0), 0.0f, tol) << "triangle " << i;
    ASSERT_NEAR(glm::length(x.v1 - y.v1), 0.0f, tol) << "triangle " << i;
    ASSERT_NEAR(glm::length(x.v2 - y.v2), 0.0f, tol) << "triangle " << i;
  }
}

TEST(Gltf, RoundTripKeepsTrianglesAndMotion) {
  TempDir dir("round");
  const Scene xml = parse_scene(kRigid, "rigid.xml", ".");
  for (const char* name : {"r.glb", "r.gltf"}) {
    write_gltf_scene(xml, dir / name);
    const Scene back = load_gltf_scene(dir / name);
    ASSERT_EQ(back.instances.size(), xml.instances.size()) << name;
    ASSERT_EQ(back.meshes.size(), xml.meshes.size());
    EXPECT_EQ(back.time_first, 0.0f);
    EXPECT_EQ(back.time_last, 3.0f);
    EXPECT_EQ(*back.meshes[0].mesh->triangles.data(), *xml.meshes[0].mesh->triangles.data());
    EXPECT_EQ(back.meshes[0].mesh->vertices, xml.meshes[0].mesh->vertices);
    for (float u : {0.0f, 0.25f, 0.5f, 0.8f, 1.0f})
      expect_near_meshes(flatten_scene(scene_at(back, u)), flatten_scene(scene_at(xml, u)), 2e-5f * 8.0f);
  }
}

TEST(Gltf, AFramesHitsAreIdenticalAcrossStructures) {
  TempDir dir("hits");
  write_gltf_scene(parse_scene(kRigid, "rigid.xml", "."), dir / "r.glb");
  const Scene scene = load_gltf_scene(dir / "r.glb");
  const auto frame = std::make_shared<const Scene>(scene_at(scene, 0.4f));
  const AABB b = frame->world_bounds();
  std::vector<Ray> rays;
  for (int i = 0; i < 600; ++i) {
    const float s = float(i % 30) / 29.0f, t = float(i / 30) / 19.0f;
    rays.push_back(
        {b.center() + vec3(0, 0, 20), b.lo + vec3(s, t, 0.5f) * b.extent() - (b.center() + vec3(0, 0, 20))});
  }
  auto brute = make_scene_accelerator(frame, "brute", Params{});
  brute->build();
  std::vector<Hit> expected(rays.size());
  trace_closest(*brute, rays, expected, 1);
  size_t found = 0;
  for (const Hit& h : expected) found += h.found();
  EXPECT_GT(found, 100u);
  for (const char* name : {"bvh-sah", "kdtree-sah", "grid"}) {
    auto accel = make_scene_accelerator(frame, name, Params{});
    accel->build();
    std::vector<Hit> hits(rays.size());
    trace_closest(*accel, rays, hits, 2);
    EXPECT_EQ(std::memcmp(hits.data(), expected.data(), hits.size() * sizeof(Hit)), 0) << name;
  }
}

/// Appends `bytes` of p to the model's one buffer as a new view and an accessor over it; its index.
int add_accessor(tinygltf::Model& m, const void* p, size_t bytes, int type, int comp, size_t count) {
  auto& buf = m.buffers[0].data;
  tinygltf::BufferView bv;
  bv.buffer = 0;
  bv.byteOffset = buf.size();
  bv.byteLength = bytes;
  buf.insert(buf.end(), (const unsigned char*)p, (const unsigned char*)p + bytes);
  while (buf.size() % 4) buf.push_back(0);
  m.bufferViews.push_back(bv);
  tinygltf::Accessor a;
  a.bufferView = int(m.bufferViews.size() - 1);
  a.type = type;
  a.componentType = comp;
  a.count = count;
  m.accessors.push_back(a);
  return int(m.accessors.size() - 1);
}

/// Animates node 0's translation with a STEP sampler over the accessors `times` and `moves`.
void add_step_translation(tinygltf::Model& m, int times, int moves) {
  tinygltf::Animation an;
  tinygltf::AnimationSampler s;
  s.input = times;
  s.output = moves;
  s.interpolation = "STEP";
  an.samplers = {s};
  tinygltf::AnimationChannel c;
  c.sampler = 0;
  c.target_node = 0;
  c.target_path = "translation";
  an.channels = {c};
  m.animations = {an};
}

/// A small model: one quad (strip) and one triangle (list) in one mesh, a parent node with a child.
tinygltf::Model small_model() {
  tinygltf::Model m;
  m.asset.version = "2.0";
  m.buffers.resize(1);
  const float pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  const uint16_t strip[] = {0, 1, 2, 3};
  const uint32_t list[] = {0, 1, 2};
  const float times[] = {0.0f, 2.0f};
  const float moves[] = {0, 0, -5, 4, 0, -5};  // replaces the parent's static translation
  const int apos = add_accessor(m, pos, sizeof pos, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, 4);
  m.accessors[size_t(apos)].minValues = {0, 0, 0};
  m.accessors[size_t(apos)].maxValues = {1, 1, 0};
  const int astrip =
      add_accessor(m, strip, sizeof strip, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, 4);
  const int alist =
      add_accessor(m, list, sizeof list, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, 3);
  const int at = add_accessor(m, times, sizeof times, TINYGLTF_TYPE_SCALAR, TINYGLTF_COMPONENT_TYPE_FLOAT, 2);
  m.accessors[size_t(at)].minValues = {0};
  m.accessors[size_t(at)].maxValues = {2};
  const int amove =
      add_accessor(m, moves, sizeof moves, TINYGLTF_TYPE_VEC3, TINYGLTF_COMPONENT_TYPE_FLOAT, 2);
  tinygltf::Mesh mesh;
  tinygltf::Primitive p;
  p.attributes["POSITION"] = apos;
  p.indices = astrip;
  p.mode = TINYGLTF_MODE_TRIANGLE_STRIP;
  mesh.primitives.push_back(p);
  p.indices = alist;
  p.mode = TINYGLTF_MODE_TRIANGLES;
  mesh.primitives.push_back(p);
  m.meshes.push_back(mesh);
  tinygltf::Node parent, child;
  parent.translation = {9, 9, 9};  // overridden by the channel
  parent.children = {1};
  parent.mesh = 0;
  child.scale = {2, 2, 2};
  child.mesh = 0;
  m.nodes = {parent, child};
  m.scenes.resize(1);
  m.scenes[0].nodes = {0};
  m.defaultScene = 0;
  add_step_translation(m, at, amove);
  return m;
}

void write_model(tinygltf::Model m, const std::string& path) {
  tinygltf::TinyGLTF w;
  const bool glb = path.back() == 'b';
  ASSERT_TRUE(w.WriteGltfSceneToFile(&m, path, true, true, !glb, glb)) << path;
}

TEST(Gltf, NodesPrimitivesAndStepChannels) {
  TempDir dir("nodes");
  write_model(small_model(), dir / "s.gltf");
  const Scene s = load_gltf_scene(dir / "s.gltf");
  ASSERT_EQ(s.meshes.size(), 1u);
  const Mesh& m = *s.meshes[0].mesh;
  ASSERT_EQ(m.size(), 3u);  // a strip of 4 indices (2 triangles), then a list of 3
  EXPECT_EQ(m.triangles[0], glm::uvec3(0, 1, 2));
  EXPECT_EQ(m.triangles[1], glm::uvec3(2, 1, 3));  // odd strip triangles swap their first two
  EXPECT_EQ(m.triangles[2], glm::uvec3(4, 5, 6));  // the second primitive's vertices follow the first's
  ASSERT_EQ(s.instances.size(), 2u);               // depth first: the parent, then its child
  EXPECT_EQ(s.instances[0].transform.point(vec3(1, 0, 0)), vec3(1, 0, -5));
  EXPECT_EQ(s.instances[1].transform.point(vec3(1, 0, 0)), vec3(2, 0, -5));
  EXPECT_EQ(s.time_last, 2.0f);
  EXPECT_EQ(scene_at(s, 0.99f).instances[1].transform.point(vec3(0)), vec3(0, 0, -5));  // STEP holds
  EXPECT_EQ(scene_at(s, 1.0f).instances[1].transform.point(vec3(0)), vec3(4, 0, -5));
  EXPECT_GT(glm::length(s.camera.eye - s.camera.look_at), 0.0f);
}

void expect_bad(const tinygltf::Model& m, const std::string& words, const std::string& file = "bad.gltf") {
  TempDir dir("bad");
  write_model(m, dir / file);
  try {
    load_gltf_scene(dir / file);
    ADD_FAILURE() << "accepted: " << words;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(dir / file, 0), 0u) << msg;
    EXPECT_NE(msg.find(words), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(Gltf, MalformedModelsAreOneLineErrors) {
  tinygltf::Model m = small_model();
  m.accessors[2].count = 50;  // more indices than the view holds
  expect_bad(m, "do not fit");
  m = small_model();
  uint32_t big = 9;
  std::memcpy(m.buffers[0].data.data() + m.bufferViews[2].byteOffset, &big, 4);
  expect_bad(m, "index 9 out of range");
  m = small_model();
  m.nodes[1].children = {0};
  expect_bad(m, "reached twice");
  m = small_model();
  m.meshes[0].primitives[0].attributes.erase("POSITION");
  expect_bad(m, "'attributes' property is not an object");  // tinygltf drops the primitive: an error
  m = small_model();
  m.meshes[0].primitives[0].attributes = {{"NORMAL", 0}};
  expect_bad(m, "has no POSITION");
  m = small_model();
  m.animations[0].channels[0].target_node = 7;
  expect_bad(m, "node 7 does not exist");
  m = small_model();
  m.animations[0].samplers[0].interpolation = "BOUNCY";
  expect_bad(m, "BOUNCY", "bad.glb");
  m = small_model();
  m.accessors[0].componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  expect_bad(m, "wrong component type");
}

TEST(Gltf, MalformedFilesAreOneLineErrors) {
  TempDir dir("files");
  write_model(small_model(), dir / "ok.glb");
  const std::string glb = test::read_text(dir / "ok.glb");
  const std::vector<std::pair<std::string, std::string>> files = {
      {"half.glb", glb.substr(0, glb.size() / 2)},
      {"head.glb", glb.substr(0, 12)},
      {"empty.glb", ""},
      {"garbage.gltf", "{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ { "},
      {"text.gltf", "hello\nworld"}};
  for (const auto& [name, bytes] : files) {
    std::ofstream(dir / name, std::ios::binary) << bytes;
    try {
      load_scene(dir / name);
      ADD_FAILURE() << "accepted " << name;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind(dir / name, 0), 0u) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
  EXPECT_THROW(load_scene(dir / "missing.gltf"), InputError);
}

TEST(Gltf, TheShippedGltfSceneIsWhatExportWrites) {
  const fs::path dir = fs::path(ACCELBENCH_SOURCE_DIR) / "datasets" / "scenes";
  TempDir tmp("shipped");
  write_gltf_scene(load_scene((dir / "carousel.xml").string()), tmp / "c.glb");
  const std::string shipped = test::read_text(dir / "carousel.glb"), fresh = test::read_text(tmp / "c.glb");
  EXPECT_EQ(shipped, fresh) << "regenerate: accelbench export --scene carousel.xml -o carousel.glb";
  const Scene s = load_scene((dir / "carousel.glb").string());
  EXPECT_TRUE(s.animated());
  EXPECT_EQ(s.time_last - s.time_first, 2.0f);
  EXPECT_EQ(s.instances.size(), 5u);
}

TEST(Gltf, CorruptedFilesLoadOrFailWithOneLine) {
  // Random byte flips and truncations of a real file: every load either gives a scene whose frames
  // evaluate, or one InputError line naming the file; nothing crashes or reads out of bounds.
  const fs::path dir = fs::path(ACCELBENCH_SOURCE_DIR) / "datasets" / "scenes";
  const std::string glb = test::read_text(dir / "carousel.glb");
  ASSERT_GT(glb.size(), 1000u);
  TempDir tmp("fuzz");
  const std::string file = tmp / "f.glb";
  uint64_t state = 12345;
  const auto next = [&] { return (state = state * 6364136223846793005ull + 1442695040888963407ull) >> 33; };
  int loaded = 0, rejected = 0;
  for (int i = 0; i < 300; ++i) {
    std::string g = i % 10 == 9 ? glb.substr(0, next() % glb.size()) : glb;
    for (int k = 0; k < 3 && i % 10 != 9; ++k) g[next() % g.size()] = char(next());
    std::ofstream(file, std::ios::binary) << g;
    try {
      const Scene s = load_gltf_scene(file);
      (void)flatten_scene(scene_at(s, 0.5f));
      ++loaded;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind(file, 0), 0u) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
      ++rejected;
    }
  }
  EXPECT_GT(rejected, 0);
  EXPECT_GT(loaded + rejected, 299);
}

TEST(GltfCli, EverySceneCommandTakesGltf) {
  if (!fs::exists(test::accelbench_exe())) GTEST_SKIP() << "accelbench binary not found";
  TempDir dir("cli");
  std::ofstream(dir / "r.xml") << kRigid;
  ASSERT_EQ(test::run_accelbench("export --scene " + dir / "r.xml" + " -o " + dir / "r.glb", dir.path).first,
            0);
  const std::string g = " --scene " + dir / "r.glb", frame = " --frame 1 --frames 3";
  for (const std::string& cmd :
       {"rays" + g + frame + " --kind primary --count 500 -o " + dir / "r.rays",
        "trace" + g + frame + " --accel bvh-sah --rays " + dir / "r.rays" + " -o " + dir / "h.hits",
        "verify" + g + frame + " --accel bvh-sah,grid --rays " + dir / "r.rays",
        "flatten" + g + " --time 0.5 -o " + dir / "f.obj",
        "render" + g + frame + " --width 16 --height 16 --spp 1 -o " + dir / "i.png"}) {
    const auto [code, err] = test::run_accelbench(cmd, dir.path);
    EXPECT_EQ(code, 0) << cmd << ": " << err;
  }
  std::ofstream(dir / "bad.glb", std::ios::binary) << "glTF\x02";
  const auto [code, err] =
      test::run_accelbench("flatten --scene " + dir / "bad.glb" + " -o " + dir / "o.obj", dir.path);
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("bad.glb: malformed glTF"), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

}  // namespace
}  // namespace ab
