// Motion blur (issue 14): the ABRAYS02 ray file, the one triangle and transform interpolation, swept and
// moving-instance bounds, and every registered structure byte-identical to brute on rays with times over
// deforming meshes and moving instances (flattened and two-level scenes, 1 and 2 threads). New structures
// are covered by registering.
#include "accel/bvh/motion.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>

#include "accel/core/error.h"
#include "accel/core/motion_prims.h"
#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "datasets/random.h"
#include "harness/compare.h"
#include "harness/hitfile.h"
#include "harness/target.h"
#include "tracer/integrator.h"
#include "tracer/scene.h"
#include "tracer/scene_accel.h"
#include "tracer/scene_motion.h"
#include "tracer/workload.h"

namespace ab {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> structure_names() {
  std::vector<std::string> names;
  for (const auto& info : accelerators())
    if (!info.is_reference && info.name.rfind("test-", 0) != 0) names.push_back(info.name);
  return names;
}

fs::path temp_path(const std::string& name) {
  return fs::temp_directory_path() / ("ab_motion_" + std::to_string(::getpid()) + "_" + name);
}

/// A soup of n small triangles in the unit cube (every third one static).
Mesh soup(size_t n, uint64_t seed) {
  Rng rng(seed);
  Mesh m;
  for (size_t i = 0; i < n; ++i) {
    const vec3 c = rng.unit_cube();
    for (int k = 0; k < 3; ++k) m.vertices.push_back(c + 0.08f * (rng.unit_cube() - vec3(0.5f)));
    m.triangles.push_back({uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  return m;
}

/// `steps` time steps of the soup: every vertex of a moving triangle displaced at random per step
/// (by up to `reach`), the static triangles (id % 3 == 0) left exactly in place.
std::vector<std::shared_ptr<const Mesh>> deforming_steps(const Mesh& base, uint32_t steps, float reach,
                                                         uint64_t seed) {
  std::vector<std::shared_ptr<const Mesh>> out;
  Rng rng(seed);
  for (uint32_t k = 0; k < steps; ++k) {
    Mesh m = base;
    for (size_t v = 0; v < m.vertices.size(); ++v)
      if ((v / 3) % 3 != 0 && k > 0) m.vertices[v] += reach * (rng.unit_cube() - vec3(0.5f));
    out.push_back(std::make_shared<const Mesh>(std::move(m)));
  }
  return out;
}

/// Rays over box with random times: random ones, ones aimed at triangle centroids at their own time,
/// axis-parallel ones, and rays at times 0 and 1 exactly.
std::vector<Ray> timed_rays(const MotionTrianglePrims* prims, const AABB& box, size_t count, uint64_t seed) {
  Rng rng(seed);
  const vec3 lo = box.lo - 0.3f * box.extent(), hi = box.hi + 0.3f * box.extent();
  std::vector<Ray> rays;
  for (size_t i = 0; i < count; ++i) {
    Ray r;
    r.org = lo + rng.unit_cube() * (hi - lo);
    r.dir = rng.unit_sphere();
    r.time = i % 11 == 0 ? float(i % 2) : rng.uniform();
    if (i % 3 == 1 && prims && prims->size()) {
      const Triangle t = prims->triangle_at(rng.below(prims->size()), r.time);
      r.dir = t.centroid() - r.org;
    }
    if (i % 7 == 2) r.dir = vec3(0.0f, 0.0f, (i % 2) ? 1.0f : -1.0f);
    rays.push_back(r);
  }
  return rays;
}

/// Brute's hits at 1 thread, then `accel` at 1 and 2 threads (closest and occluded), byte for byte.
void expect_same_as_brute(const Accelerator& accel, const Accelerator& brute, const std::vector<Ray>& rays,
                          const std::string& what) {
  std::vector<Hit> expected(rays.size());
  trace_closest(brute, rays, expected, 1);
  size_t found = 0;
  for (const Hit& h : expected) found += h.found();
  EXPECT_GT(found, rays.size() / 20) << what << ": too few hits to test anything";
  for (int threads : {1, 2}) {
    std::vector<Hit> hits(rays.size());
    trace_closest(accel, rays, hits, threads);
    const IdenticalResult r = compare_identical(expected, hits);
    ASSERT_TRUE(r.identical()) << what << ", " << threads << " thread(s): " << r.differing << " of "
                               << rays.size() << " rays differ (first " << r.first_differences.front() << ")";
  }
  std::vector<uint8_t> occluded(rays.size());
  trace_occluded(accel, rays, occluded, 2);
  for (size_t i = 0; i < rays.size(); ++i)
    ASSERT_EQ(occluded[i] != 0, expected[i].found()) << what << ": occluded() differs on ray " << i;
}

TEST(MotionRayFile, VersionOneStaysByteForByteAndVersionTwoKeepsTimes) {
  std::vector<Ray> rays = timed_rays(nullptr, {vec3(0), vec3(1)}, 50, 3);
  const fs::path v1 = temp_path("v1.rays"), v2 = temp_path("v2.rays");
  write_rays(v1.string(), rays);
  write_rays(v2.string(), rays, RayFileVersion::kV2);
  EXPECT_EQ(fs::file_size(v1), 16u + 50u * 32u);
  EXPECT_EQ(fs::file_size(v2), 16u + 50u * 36u);
  EXPECT_EQ(ray_record_bytes(v1.string()), 32u);
  EXPECT_EQ(ray_record_bytes(v2.string()), 36u);
  const std::vector<Ray> back1 = read_rays(v1.string()), back2 = read_rays(v2.string());
  ASSERT_EQ(back1.size(), rays.size());
  ASSERT_EQ(back2.size(), rays.size());
  EXPECT_EQ(std::memcmp(back2.data(), rays.data(), rays.size() * sizeof(Ray)), 0);
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(back1[i].time, 0.0f);
    EXPECT_EQ(std::memcmp(&back1[i], &rays[i], 32), 0);
  }
  std::ifstream in(v1, std::ios::binary);
  char magic[8];
  in.read(magic, 8);
  EXPECT_EQ(std::string(magic, 8), "ABRAYS01");
  fs::remove(v1);
  fs::remove(v2);
}

TEST(MotionRayFile, BadTimesAreBadInput) {
  for (float bad : {std::nanf(""), -0.25f, 1.5f, kInf}) {
    std::vector<Ray> rays(3);
    rays[1].time = bad;
    const fs::path p = temp_path("bad.rays");
    write_rays(p.string(), rays, RayFileVersion::kV2);
    try {
      read_rays(p.string());
      ADD_FAILURE() << "time " << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("ray 1"), std::string::npos) << e.what();
    }
    fs::remove(p);
  }
}

TEST(MotionRayFile, OnlyTmaxMayBeInfiniteAndOnlyPlusInfinity) {
  // The contract: "tmax may be +inf"; -inf there (every ray an empty interval) is bad input like tmin's.
  for (RayFileVersion version : {RayFileVersion::kV1, RayFileVersion::kV2}) {
    std::vector<Ray> rays(3);
    rays[0].tmax = kInf;
    const fs::path p = temp_path("tmax.rays");
    write_rays(p.string(), rays, version);
    EXPECT_EQ(read_rays(p.string()).size(), 3u);
    for (int field : {0, 1}) {
      std::vector<Ray> bad = rays;
      (field == 0 ? bad[2].tmax : bad[2].tmin) = -kInf;
      write_rays(p.string(), bad, version);
      try {
        read_rays(p.string());
        ADD_FAILURE() << (field == 0 ? "tmax" : "tmin") << " = -inf was accepted";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("ray 2"), std::string::npos) << e.what();
      }
    }
    fs::remove(p);
  }
}

TEST(MotionPrims, InterpolationHitsTheStepsAndStaysInsideTheSweptBox) {
  const Mesh base = soup(200, 5);
  const auto steps = deforming_steps(base, 4, 0.3f, 6);
  const MotionTrianglePrims prims(steps);
  ASSERT_EQ(prims.size(), 200u);
  for (size_t i = 0; i < prims.size(); ++i) {
    EXPECT_EQ(prims.moves(i), i % 3 != 0);
    for (uint32_t k = 0; k < 4; ++k) {
      const Triangle at = prims.triangle_at(i, float(k) / 3.0f), step = steps[k]->triangle(i);
      EXPECT_EQ(std::memcmp(&at, &step, sizeof(Triangle)), 0) << i << " step " << k;
    }
    for (int s = 0; s <= 200; ++s) {
      const Triangle t = prims.triangle_at(i, float(s) / 200.0f);
      const AABB b = prims.bounds(i);
      for (const vec3& v : {t.v0, t.v1, t.v2}) ASSERT_TRUE(b.contains(v)) << i << " at " << s;
    }
  }
}

/// An instance of a unit cube spinning about a tilted axis by `degrees` over the shutter (with a
/// translation), sampled at `steps` time steps.
Instance spinning_instance(std::shared_ptr<const Accelerator> base, float degrees, uint32_t steps) {
  Instance inst{base, glm::mat4(1.0f), glm::mat4(1.0f), 0, {}};
  for (uint32_t k = 0; k < steps; ++k) {
    const float f = float(k) / float(steps - 1);
    glm::mat4 m = glm::translate(glm::mat4(1.0f), vec3(3.0f * f, 1.0f, -2.0f));
    m = glm::rotate(m, glm::radians(degrees * f), glm::normalize(vec3(1, 2, 0.5f)));
    inst.to_world_steps.push_back(glm::scale(m, vec3(1.0f + f, 0.5f, 1.5f)));
  }
  inst.to_world = inst.to_world_steps.front();
  inst.to_object = glm::inverse(inst.to_world);
  return inst;
}

TEST(MotionInstances, SampledPositionsStayInsideTheBoundsOverLargeRotations) {
  Mesh cube;
  for (int c = 0; c < 8; ++c) cube.vertices.push_back(vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1) - vec3(0.5f));
  cube.triangles = {{0, 1, 3}, {0, 3, 2}, {4, 5, 7}, {4, 7, 6}};
  auto base = make_accelerator(
      "brute", std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(cube)), Params{});
  base->build();
  std::shared_ptr<const Accelerator> shared = std::move(base);
  for (float degrees : {30.0f, 180.0f, 359.0f, 720.0f})
    for (uint32_t steps : {2u, 3u, 9u}) {
      const Instance inst = spinning_instance(shared, degrees, steps);
      const AABB world = instance_world_bounds(inst);
      for (int s = 0; s <= 1000; ++s) {
        const glm::mat4 m = instance_to_world_at(inst, float(s) / 1000.0f);
        for (const vec3& v : cube.vertices)
          ASSERT_TRUE(world.contains(vec3(m * glm::vec4(v, 1.0f)))) << degrees << " " << steps << " " << s;
      }
    }
}

class MotionConformance : public ::testing::TestWithParam<std::string> {};

TEST_P(MotionConformance, DeformingMeshes) {
  for (uint32_t steps : {2u, 5u}) {
    auto prims = std::make_shared<const MotionTrianglePrims>(deforming_steps(soup(400, 7), steps, 0.25f, 8));
    auto accel = make_motion_accelerator(GetParam(), prims, Params{});
    accel->build();
    auto brute = make_motion_accelerator("brute", prims, Params{});
    brute->build();
    EXPECT_EQ(accel->bounds().lo, prims->bounds().lo);
    expect_same_as_brute(*accel, *brute, timed_rays(prims.get(), prims->bounds(), 2000, steps),
                         GetParam() + " over " + std::to_string(steps) + " steps");
  }
}

/// Twelve instances over two bases (a deforming soup and a static one): every other one spinning.
std::shared_ptr<const InstancePrims> moving_instances(std::shared_ptr<const Accelerator> moving,
                                                      std::shared_ptr<const Accelerator> fixed) {
  std::vector<Instance> list;
  for (int i = 0; i < 12; ++i) {
    auto base = i % 3 == 0 ? fixed : moving;
    if (i % 2) {
      Instance inst = spinning_instance(base, 40.0f * float(i), 2 + uint32_t(i % 4));
      for (glm::mat4& m : inst.to_world_steps)
        m = glm::translate(glm::mat4(1.0f), vec3(float(i % 4), 0, 0)) * m;
      list.push_back(inst);
    } else {
      const glm::mat4 m = glm::translate(glm::mat4(1.0f), vec3(float(i % 4) * 1.5f, float(i / 4), 0.0f));
      list.push_back({base, m, glm::inverse(m), 0, {}});
    }
  }
  return std::make_shared<const InstancePrims>(std::move(list));
}

TEST_P(MotionConformance, MovingInstancesAtBothLevels) {
  auto steps = deforming_steps(soup(150, 9), 3, 0.2f, 10);
  auto motion = std::make_shared<const MotionTrianglePrims>(steps);
  auto fixed = std::make_shared<const TrianglePrims>(steps.front());
  auto built = [](std::unique_ptr<Accelerator> a) {
    a->build();
    return std::shared_ptr<const Accelerator>(std::move(a));
  };
  auto brute_moving = built(make_motion_accelerator("brute", motion, Params{}));
  auto brute_fixed = built(make_accelerator("brute", fixed, Params{}));
  auto all_brute = built(make_instance_accelerator("brute", moving_instances(brute_moving, brute_fixed), {}));
  std::vector<Ray> rays = timed_rays(nullptr, all_brute->bounds(), 2000, 11);
  const auto placed = moving_instances(brute_moving, brute_fixed);
  Rng rng(12);
  for (size_t k = 0; k < rays.size(); k += 2) {  // every other ray aimed into an instance at its time
    const Instance& inst = placed->instance(rng.below(placed->size()));
    const glm::mat4 m = inst.moves() ? instance_to_world_at(inst, rays[k].time) : inst.to_world;
    const Triangle t = motion->triangle_at(rng.below(motion->size()), rays[k].time);
    rays[k].dir = vec3(m * glm::vec4(t.centroid(), 1.0f)) - rays[k].org;
  }
  auto top = built(make_instance_accelerator(GetParam(), moving_instances(brute_moving, brute_fixed), {}));
  expect_same_as_brute(*top, *all_brute, rays, GetParam() + " as top level");
  auto bottom = built(
      make_instance_accelerator("brute",
                                moving_instances(built(make_motion_accelerator(GetParam(), motion, Params{})),
                                                 built(make_accelerator(GetParam(), fixed, Params{}))),
                                {}));
  expect_same_as_brute(*bottom, *all_brute, rays, GetParam() + " as bottom level");
}

/// The shipped motion scene (datasets/scenes/motion.xml) at a frame inside the animation.
std::shared_ptr<const Scene> motion_scene(float time = 0.3f) {
  const Scene s = load_scene(std::string(ACCELBENCH_SOURCE_DIR) + "/datasets/scenes/motion.xml");
  return std::make_shared<const Scene>(scene_at(s, time));
}

/// The scene's primary rays with times (the `motion` kind), plus rays at random times through its bounds.
std::vector<Ray> scene_rays(const Scene& scene, const AABB& bounds, const Accelerator& brute) {
  std::vector<Ray> rays = make_scene_rays(
      scene, [&](std::span<const Ray> r, std::span<Hit> h) { brute.intersect(r, h); }, "motion", 1500, 4);
  const std::vector<Ray> more = timed_rays(nullptr, bounds, 500, 5);
  rays.insert(rays.end(), more.begin(), more.end());
  return rays;
}

TEST(MotionScene, TheShippedSceneMovesAnInstanceAndDeformsMeshes) {
  const auto scene = motion_scene();
  const SceneMotion motion = scene_motion(*scene);
  ASSERT_TRUE(motion.any());
  EXPECT_EQ(motion.step_times.size(), 5u);
  size_t moving_meshes = 0, moving_instances = 0;
  for (const auto& m : motion.meshes) moving_meshes += !m.empty();
  for (const auto& i : motion.instances) moving_instances += !i.empty();
  EXPECT_EQ(moving_meshes, 2u);
  EXPECT_EQ(moving_instances, 1u);
  EXPECT_FLOAT_EQ(shutter_scene_time(*scene, 0.0f), 0.3f);
  EXPECT_FLOAT_EQ(shutter_scene_time(*scene, 1.0f), 0.35f);
}

TEST_P(MotionConformance, ShippedSceneTwoLevelAndFlattened) {
  const auto scene = motion_scene();
  auto brute = make_scene_accelerator(scene, "brute", Params{});
  brute->build();
  const std::vector<Ray> rays = scene_rays(*scene, brute->bounds(), *brute);
  auto accel = make_scene_accelerator(scene, GetParam(), Params{});
  accel->build();
  expect_same_as_brute(*accel, *brute, rays, GetParam() + " two-level");
  auto flat = std::make_shared<const MotionTrianglePrims>(flatten_scene_motion(*scene, scene_motion(*scene)));
  auto flat_brute = make_motion_accelerator("brute", flat, Params{});
  flat_brute->build();
  auto flat_accel = make_motion_accelerator(GetParam(), flat, Params{});
  flat_accel->build();
  expect_same_as_brute(*flat_accel, *flat_brute, rays, GetParam() + " flattened");
}

TEST(MotionScene, StaticScenesAndAClosedShutterIgnoreRayTimes) {
  Scene closed = *motion_scene();
  closed.camera.shutter_close = closed.camera.shutter_open;
  auto scene = std::make_shared<const Scene>(closed);
  ASSERT_FALSE(scene_motion(*scene).any());
  for (const std::string name : {"brute", "bvh-sah", "grid"}) {
    auto accel = make_scene_accelerator(scene, name, Params{});
    accel->build();
    std::vector<Ray> rays = scene_rays(*scene, accel->bounds(), *accel), at_zero = rays;
    for (Ray& r : at_zero) r.time = 0.0f;
    std::vector<Hit> a(rays.size()), b(rays.size());
    trace_closest(*accel, rays, a, 2);
    trace_closest(*accel, at_zero, b, 2);
    EXPECT_TRUE(compare_identical(a, b).identical()) << name;
  }
}

TEST(MotionScene, RenderIsTheSameOnAnyThreadCountAndShowsBlur) {
  const auto scene = motion_scene();
  auto accel = make_scene_accelerator(scene, "bvh-motion", Params{});
  accel->build();
  RenderOptions o = render_options(*scene);
  o.width = 48;
  o.height = 36;
  o.spp = 4;
  o.threads = 1;
  const Image one = render(*scene, *accel, o);
  o.threads = 2;
  const Image two = render(*scene, *accel, o);
  EXPECT_EQ(std::memcmp(one.pixels.data(), two.pixels.data(), one.pixels.size() * sizeof(vec3)), 0);
  Scene closed = *scene;
  closed.camera.shutter_close = closed.camera.shutter_open;
  auto still = std::make_shared<const Scene>(closed);
  auto still_accel = make_scene_accelerator(still, "bvh-motion", Params{});
  still_accel->build();
  const Image sharp = render(*still, *still_accel, o);
  EXPECT_NE(std::memcmp(one.pixels.data(), sharp.pixels.data(), one.pixels.size() * sizeof(vec3)), 0);
}

TEST(MotionBvh, PrimitivesThatDoNotMoveGetTheStaticTree) {
  const Mesh base = soup(300, 21);
  auto fixed = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(base));
  auto moving = std::make_shared<const MotionTrianglePrims>(deforming_steps(base, 3, 0.2f, 22));
  const auto same = std::make_shared<const Mesh>(base);
  auto still =
      std::make_shared<const MotionTrianglePrims>(std::vector<std::shared_ptr<const Mesh>>{same, same});
  BvhMotion<TrianglePrims> over_fixed(fixed, BvhMotionConfig{});
  BvhMotion<MotionTrianglePrims> over_moving(moving, BvhMotionConfig{}), over_still(still, BvhMotionConfig{});
  over_fixed.build(), over_moving.build(), over_still.build();
  EXPECT_TRUE(over_fixed.uses_static_tree());
  EXPECT_FALSE(over_moving.uses_static_tree());
  EXPECT_TRUE(over_still.uses_static_tree());
  EXPECT_EQ(over_fixed.stats().extra["static_tree"], true);
  EXPECT_EQ(over_moving.stats().extra["static_tree"], false);
  auto brute_still = make_motion_accelerator("brute", still, Params{});
  brute_still->build();
  expect_same_as_brute(over_still, *brute_still, timed_rays(still.get(), still->bounds(), 1000, 23),
                       "bvh-motion over a mesh that does not move");
  auto brute = make_motion_accelerator("brute", moving, Params{});
  brute->build();
  auto fixed_brute = make_accelerator("brute", fixed, Params{});
  fixed_brute->build();
  const auto instances = moving_instances(std::move(brute), std::move(fixed_brute));
  std::vector<Instance> fixed_list;
  for (size_t i = 0; i < instances->size(); ++i)
    if (!instances->instance(i).moves()) fixed_list.push_back(instances->instance(i));
  BvhMotion<InstancePrims> top_moving(instances, BvhMotionConfig{});
  BvhMotion<InstancePrims> top_fixed(std::make_shared<const InstancePrims>(fixed_list), BvhMotionConfig{});
  top_moving.build(), top_fixed.build();
  EXPECT_FALSE(top_moving.uses_static_tree());
  EXPECT_TRUE(top_fixed.uses_static_tree());
}

TEST(MotionBvh, TheWideNodeEntersALaneOnlyAtTimesInItsRange) {
  const LinearBounds lb{AABB{vec3(0.0f), vec3(1.0f)}, AABB{vec3(2.0f, 0.0f, 0.0f), vec3(3.0f, 1.0f, 1.0f)}};
  MotionBvh8Node node;
  node.set(0, MotionBvhNode::make(lb, 0.0f, 0.5f));
  node.set(1, MotionBvhNode::make(lb, 0.5f, 1.0f));
  node.count[0] = node.count[1] = 1;
  Ray ray;
  ray.org = vec3(-5.0f, 0.5f, 0.5f), ray.dir = vec3(1.0f, 0.0f, 0.0f);
  for (float time : {0.0f, 0.25f, 0.5f, 0.75f, 1.0f}) {
    ray.time = time;
    const MotionBvh8RayTest test(ray);
    alignas(32) float t[8];
    const unsigned mask = test.entries(node, kInf, t);
    EXPECT_EQ(mask, (time <= 0.5f ? 1u : 0u) | (time >= 0.5f ? 2u : 0u)) << time;
    EXPECT_EQ(test.entries_scalar(node, kInf, t), mask) << time;
    const float f = time <= 0.5f ? time / 0.5f : (time - 0.5f) / 0.5f;     // lane 0 or 1's fraction
    EXPECT_NEAR(t[time <= 0.5f ? 0 : 1], 5.0f + 2.0f * f, 1e-3f) << time;  // enters its box at that time
  }
}

/// Triangles far from the origin whose top edges all move alike in y, and rays parallel to x and z exactly
/// on the edge at the ray's time: the interpolated boxes end on the edge's y to within rounding, so only the
/// margin (kMotionBoxEps) keeps them from culling the hit.
TEST(MotionBvh, RaysOnAMovingEdgeAreNotCulledByRounding) {
  std::vector<std::shared_ptr<const Mesh>> steps;
  for (const float y : {1000.0f, 1003.3f}) {  // linear motion: the linear bounds are exact
    Mesh m;
    for (uint32_t i = 0; i < 64; ++i) {
      const float x = 1000.0f + float(i % 8), z = 1000.0f + float(i / 8);
      m.vertices.push_back({x, y - 0.7f, z});
      m.vertices.push_back({x - 0.4f, y, z});
      m.vertices.push_back({x + 0.4f, y, z});
      m.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
    }
    steps.push_back(std::make_shared<const Mesh>(std::move(m)));
  }
  auto prims = std::make_shared<const MotionTrianglePrims>(steps);
  Rng rng(31);
  std::vector<Ray> rays;
  for (int k = 0; k < 4000; ++k) {
    Ray r;
    r.time = rng.uniform();
    const size_t i = rng.below(prims->size());
    const Triangle t = prims->triangle_at(i, r.time);
    const float along = 0.9f * (rng.uniform() - 0.5f);
    r.org = 0.5f * (t.v1 + t.v2) + vec3(0.4f * along, 0.0f, -0.5f);
    r.dir = vec3(0.0f, 0.0f, 1.0f);
    rays.push_back(r);
  }
  auto brute = make_motion_accelerator("brute", prims, Params{});
  brute->build();
  for (const char* width : {"8", "2"}) {
    Params p;
    p.set("width", width);
    auto accel = make_motion_accelerator("bvh-motion", prims, p);
    accel->build();
    expect_same_as_brute(*accel, *brute, rays, std::string("bvh-motion width ") + width);
  }
}

TEST(MotionBvh, BinaryWidthIsBruteAndTheParallelBuildIsTheSerialTree) {
  auto prims = std::make_shared<const MotionTrianglePrims>(deforming_steps(soup(3000, 41), 5, 0.3f, 42));
  Params p;
  p.set("width", "2");
  auto binary = make_motion_accelerator("bvh-motion", prims, p);
  binary->build();
  auto brute = make_motion_accelerator("brute", prims, Params{});
  brute->build();
  expect_same_as_brute(*binary, *brute, timed_rays(prims.get(), prims->bounds(), 1500, 43), "width 2");
  const auto wide_tree = [&](size_t threshold, int threads) {
    BvhMotionConfig c;
    c.parallel_threshold = threshold;
    BvhMotion<MotionTrianglePrims> accel(prims, c);
    tbb::task_arena(threads).execute([&] { accel.build(); });
    const MotionBvh8NodeArray& nodes = accel.wide_nodes();
    return std::vector<char>(reinterpret_cast<const char*>(nodes.data()),
                             reinterpret_cast<const char*>(nodes.data() + nodes.size()));
  };
  const std::vector<char> serial = wide_tree(size_t(1) << 40, 1);
  EXPECT_GT(serial.size(), 10 * sizeof(MotionBvh8Node));
  EXPECT_EQ(wide_tree(64, 1), serial);
  EXPECT_EQ(wide_tree(64, 2), serial);
}

TEST(MotionScene, VerifyExplainsHitsWithTheTrianglesAtTheRayTime) {
  const auto scene = motion_scene();
  auto brute = make_scene_accelerator(scene, "brute", Params{});
  brute->build();
  const std::vector<Ray> rays = scene_rays(*scene, brute->bounds(), *brute);
  std::vector<Hit> hits(rays.size());
  trace_closest(*brute, rays, hits, 2);
  const HitTriangleAtFn triangle_at = hit_triangles(scene_target(scene, "motion.xml"));
  size_t on_triangle = 0, off_at_time_zero = 0, found = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!hits[i].found()) continue;
    ++found;
    const Hit& h = hits[i];
    const vec3 p = rays[i].org + h.t * rays[i].dir;
    const auto distance = [&](const Triangle& t) {
      return glm::length((1.0f - h.u - h.v) * t.v0 + h.u * t.v1 + h.v * t.v2 - p);
    };
    on_triangle += distance(triangle_at(h, rays[i].time)) < 1e-3f;
    off_at_time_zero += distance(triangle_at(h, 0.0f)) > 1e-2f;
  }
  EXPECT_GT(found, rays.size() / 4);
  EXPECT_EQ(on_triangle, found);     // the hit point is on its triangle at the ray's time
  EXPECT_GT(off_at_time_zero, 20u);  // and, for moving parts, not on the one at the frame's time
}

INSTANTIATE_TEST_SUITE_P(Structures, MotionConformance, ::testing::ValuesIn(structure_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string s = info.param;
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

}  // namespace
}  // namespace ab
