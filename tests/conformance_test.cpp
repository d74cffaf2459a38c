// Every registered structure of the project against brute force: byte-identical hits, the same
// occlusion answers, at 1 and 2 threads, as bottom and as top level, on adversarial meshes and rays,
// on every generator and ray kind, and on the real meshes. New structures are covered by registering.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>

#include "accel/core/registry.h"
#include "accel/core/trace.h"
#include "accel/reference/brute.h"
#include "datasets/generators.h"
#include "datasets/mesh_io.h"
#include "datasets/random.h"
#include "datasets/rays.h"
#include "harness/compare.h"

namespace ab {
namespace {

std::vector<std::string> structure_names() {
  std::vector<std::string> names;
  for (const auto& info : accelerators())
    if (!info.is_reference && info.name.rfind("test-", 0) != 0) names.push_back(info.name);
  if (names.empty()) names.push_back("brute");  // keeps the suite non-empty before structures land
  return names;
}

std::shared_ptr<const Mesh> share(Mesh m) {
  return std::make_shared<const Mesh>(std::move(m));
}

void add_triangle(Mesh& m, vec3 a, vec3 b, vec3 c) {
  const uint32_t base = static_cast<uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {a, b, c});
  m.triangles.push_back({base, base + 1, base + 2});
}

/// Axis-aligned unit cubes on an integer lattice: faces lie exactly on likely split planes, and
/// neighbouring cubes share faces (coplanar duplicates with opposite orientation).
Mesh lattice_cubes() {
  Mesh m;
  for (int x = 0; x < 3; ++x)
    for (int y = 0; y < 3; ++y)
      for (int z = 0; z < 2; ++z) {
        if ((x + y + z) % 2) continue;
        const vec3 o(x, y, z);
        for (int axis = 0; axis < 3; ++axis)
          for (int side = 0; side < 2; ++side) {
            vec3 a(0), b(0), c(0), d(0);
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            a[axis] = b[axis] = c[axis] = d[axis] = float(side);
            b[u] = 1;
            c[u] = 1;
            c[v] = 1;
            d[v] = 1;
            add_triangle(m, o + a, o + b, o + c);
            add_triangle(m, o + a, o + c, o + d);
          }
      }
  return m;
}

/// Flat geometry: every triangle in the plane z = 0.5 (a zero-thickness bounding box).
Mesh flat_sheet() {
  Mesh m;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      const vec3 o(i, j, 0.5f);
      add_triangle(m, o, o + vec3(1, 0, 0), o + vec3(1, 1, 0));
      add_triangle(m, o, o + vec3(1, 1, 0), o + vec3(0, 1, 0));
    }
  return m;
}

/// Duplicates, degenerate triangles (points, repeated vertices, collinear) and a tiny object in a huge box.
Mesh nasty_mix() {
  Mesh m;
  Rng rng(7);
  for (int i = 0; i < 40; ++i) {
    const vec3 a = rng.unit_cube(), b = rng.unit_cube(), c = rng.unit_cube();
    add_triangle(m, a, b, c);
    if (i % 5 == 0) add_triangle(m, a, b, c);               // exact duplicate
    if (i % 7 == 0) add_triangle(m, a, a, a);               // point
    if (i % 6 == 0) add_triangle(m, a, b, b);               // repeated vertex
    if (i % 9 == 0) add_triangle(m, a, 0.5f * (a + b), b);  // collinear
  }
  add_triangle(m, {-1000, -1000, -1000}, {1000, -1000, -1000}, {1000, 1000, -1000});  // the stadium floor
  add_triangle(m, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f});
  return m;
}

/// Pages around a spine: triangles sharing one edge (the z axis), fanned around it at every angle, so every
/// plane through the spine cuts them all and every ray near it crosses many.
Mesh pages_around_edge() {
  Mesh m;
  Rng rng(3);
  for (int i = 0; i < 60; ++i) {
    const float a = 6.2831853f * float(i) / 60.0f;
    add_triangle(m, {0, 0, 0}, {0, 0, 1}, {std::cos(a), std::sin(a), rng.uniform()});
  }
  return m;
}

/// Copies of one triangle stacked one float ulp apart (z = 1, its successor, ...), with triangles crossing
/// the stack: neighbours no margin or plane can tell apart.
Mesh ulp_stack() {
  Mesh m;
  Rng rng(5);
  float z = 1.0f;
  for (int i = 0; i < 40; ++i) {
    add_triangle(m, {-1, -1, z}, {1, -1, z}, {0, 1, z});
    z = std::nextafter(z, 2.0f);
    if (i % 4 != 0) continue;
    const float x0 = rng.uniform(-1, 1), x1 = rng.uniform(-1, 1), x2 = rng.uniform(-1, 1);
    add_triangle(m, {x0, -1, 0.5f}, {x1, 1, 1.5f}, {x2, 0, 1});
  }
  return m;
}

/// A cluster of triangles of 1e-3 in 2e-2 on a ground of 2e4 (a millionth of the scene): detail below the
/// spatial trees' root-relative insertion margin.
Mesh cluster_on_ground() {
  Mesh m;
  add_triangle(m, {-1e4f, -1e4f, 0}, {1e4f, -1e4f, 0}, {1e4f, 1e4f, 0});
  add_triangle(m, {-1e4f, -1e4f, 0}, {1e4f, 1e4f, 0}, {-1e4f, 1e4f, 0});
  Rng rng(9);
  for (int i = 0; i < 80; ++i) {
    const vec3 c = vec3(2e-2f, 2e-2f, 2e-2f) * rng.unit_cube() - vec3(1e-2f, 1e-2f, 0);
    auto corner = [&] { return c + 2e-3f * rng.unit_cube() - vec3(1e-3f); };
    const vec3 a = corner(), b = corner();
    add_triangle(m, a, b, corner());
  }
  return m;
}

Mesh one_triangle() {
  Mesh m;
  add_triangle(m, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  return m;
}

/// Adversarial rays for a mesh: random, axis-parallel (zero components, +0 and -0), aimed at vertices and
/// edge midpoints, starting on surfaces, lying in axis planes through vertices, and with tmin/tmax cut at
/// the brute-force hit distance.
std::vector<Ray> adversarial_rays(const Mesh& mesh, const AABB& box, uint64_t seed) {
  std::vector<Ray> rays;
  Rng rng(seed);
  const AABB b = box.empty() ? AABB{vec3(0), vec3(1)} : box;
  const vec3 lo = b.lo - 0.25f * (b.extent() + vec3(1)), hi = b.hi + 0.25f * (b.extent() + vec3(1));
  auto point = [&] { return lo + rng.unit_cube() * (hi - lo); };
  for (int i = 0; i < 300; ++i) rays.push_back({point(), rng.unit_sphere(), 0.0f, kInf});
  for (int i = 0; i < 300; ++i) {  // axis-parallel rays, also with -0 components
    Ray r{point(), vec3(0.0f), 0.0f, kInf};
    const int axis = i % 3;
    r.dir[axis] = (i / 3) % 2 ? 1.0f : -1.0f;
    if (i % 4 == 0) r.dir[(axis + 1) % 3] = -0.0f;
    rays.push_back(r);
  }
  for (size_t t = 0; t < mesh.size() && rays.size() < 2400; t += 1 + mesh.size() / 400) {
    const Triangle tri = mesh.triangle(t);
    const vec3 targets[4] = {tri.v0, 0.5f * (tri.v0 + tri.v1), 0.5f * (tri.v1 + tri.v2), tri.centroid()};
    for (const vec3& target : targets) {
      const vec3 o = point();
      rays.push_back({o, target - o, 0.0f, kInf});  // at a vertex / edge / centre, t = 1
    }
    rays.push_back({tri.centroid(), rng.unit_sphere(), 0.0f, kInf});  // starting on the surface
    Ray in_plane{tri.v0 - vec3(b.extent().x + 1, 0, 0), vec3(1, 0, 0), 0.0f,
                 kInf};  // in the axis planes of v0
    rays.push_back(in_plane);
    // Lying in the triangle's own (generally oblique) plane, along an edge direction and across it.
    rays.push_back({tri.v0 - (tri.v1 - tri.v0), tri.v1 - tri.v0, 0.0f, kInf});
    rays.push_back(
        {tri.v0 - 0.5f * (tri.v1 + tri.v2 - 2.0f * tri.v0), 0.5f * (tri.v1 + tri.v2) - tri.v0, 0.0f, kInf});
    Ray limited{point(), tri.centroid(), 0.0f, 1.0f};
    limited.dir = tri.centroid() - limited.org;
    rays.push_back(limited);  // tmax exactly at the hit
    limited.tmin = 1.0f;
    limited.tmax = kInf;
    rays.push_back(limited);  // tmin exactly at the hit
  }
  rays.push_back({b.center(), vec3(0.0f), 0.0f, kInf});  // zero direction
  return rays;
}

std::string hit_string(const Hit& h) {
  return "t=" + std::to_string(h.t) + " prim=" + std::to_string(h.prim) + " inst=" + std::to_string(h.inst) +
         " u=" + std::to_string(h.u) + " v=" + std::to_string(h.v);
}

/// A ray's floats in hexadecimal (exact, to reproduce a failure).
std::string ray_string(const Ray& r) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "org (%a, %a, %a) dir (%a, %a, %a) tmin %a tmax %a", r.org.x, r.org.y,
                r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tmin, r.tmax);
  return buf;
}

/// Traces rays with `name` at 1 and 2 threads (closest, counted, occluded) and expects brute's bits.
void expect_same_as_brute(const Accelerator& accel, const Accelerator& brute, const std::vector<Ray>& rays,
                          const std::string& what) {
  std::vector<Hit> expected(rays.size());
  trace_closest(brute, rays, expected, 1);
  for (int threads : {1, 2}) {
    std::vector<Hit> hits(rays.size());
    trace_closest(accel, rays, hits, threads);
    const IdenticalResult r = compare_identical(expected, hits);
    ASSERT_TRUE(r.identical()) << what << ", " << threads << " thread(s): " << r.differing << " of "
                               << rays.size() << " rays differ; first ray " << r.first_differences.front()
                               << ": expected " << hit_string(expected[r.first_differences.front()])
                               << ", got " << hit_string(hits[r.first_differences.front()]) << "; ray "
                               << ray_string(rays[r.first_differences.front()]);
  }
  std::vector<Hit> counted(rays.size());
  const RayCounters c = trace_closest_counted(accel, rays, counted, 2);
  EXPECT_TRUE(compare_identical(expected, counted).identical()) << what << ": the counting pass changed hits";
  EXPECT_GT(c.prims + c.nodes + (rays.empty() ? 1 : 0) + (accel.bounds().empty() ? 1 : 0), 0u) << what;
  std::vector<uint8_t> occluded(rays.size());
  trace_occluded(accel, rays, occluded, 2);
  for (size_t i = 0; i < rays.size(); ++i)
    ASSERT_EQ(occluded[i] != 0, expected[i].found())
        << what << ": occluded() disagrees with brute on ray " << i;
}

void check_mesh(const std::string& name, std::shared_ptr<const Mesh> mesh, const std::vector<Ray>& rays,
                const std::string& what) {
  auto prims = std::make_shared<const TrianglePrims>(mesh);
  auto accel = make_accelerator(name, prims, Params{});
  accel->build();
  auto brute = make_accelerator("brute", prims, Params{});
  brute->build();
  expect_same_as_brute(*accel, *brute, rays, what);
}

class Conformance : public ::testing::TestWithParam<std::string> {};

TEST_P(Conformance, AdversarialMeshesAndRays) {
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"empty mesh", Mesh{}},
      {"one triangle", one_triangle()},
      {"flat sheet", flat_sheet()},
      {"lattice cubes", lattice_cubes()},
      {"duplicates and degenerates", nasty_mix()},
      {"pages around an edge", pages_around_edge()},
      {"a stack one ulp apart", ulp_stack()},
      {"a cluster on a huge ground", cluster_on_ground()}};
  for (const auto& [what, mesh] : meshes) {
    auto shared = share(mesh);
    check_mesh(GetParam(), shared, adversarial_rays(mesh, mesh.bounds(), 11), what);
  }
}

TEST_P(Conformance, EveryGeneratorAndRayKind) {
  ASSERT_FALSE(generators().empty());
  for (const auto& gen : generators()) {
    auto mesh = share(generate_mesh(gen.name, 3000, 5, Params{}));
    auto prims = std::make_shared<const TrianglePrims>(mesh);
    auto brute = make_accelerator("brute", prims, Params{});
    brute->build();
    RayTarget target;
    target.bounds = mesh->bounds();
    target.trace = [&](std::span<const Ray> r, std::span<Hit> h) { brute->intersect(r, h); };
    target.normal = [&](const Hit& h) {
      const Triangle t = mesh->triangle(h.prim);
      const vec3 n = glm::cross(t.v1 - t.v0, t.v2 - t.v0);
      return glm::length(n) > 0 ? glm::normalize(n) : vec3(0, 0, 1);
    };
    auto accel = make_accelerator(GetParam(), prims, Params{});
    accel->build();
    for (const auto& kind : ray_kinds()) {
      const std::vector<Ray> rays = make_rays(kind.name, target, 1500, 3);
      expect_same_as_brute(*accel, *brute, rays, gen.name + " / " + kind.name);
    }
    expect_same_as_brute(*accel, *brute, adversarial_rays(*mesh, mesh->bounds(), 13),
                         gen.name + " / adversarial");
  }
}

TEST_P(Conformance, RealMeshes) {
  const std::filesystem::path dir = std::filesystem::path(ACCELBENCH_SOURCE_DIR) / ".." / "shared" / "meshes";
  if (!std::filesystem::exists(dir / "teapot.obj")) GTEST_SKIP() << "the real meshes are not at " << dir;
  for (const char* file : {"teapot.obj", "stanford-bunny.obj"}) {
    auto mesh = share(read_mesh((dir / file).string()));
    check_mesh(GetParam(), mesh, adversarial_rays(*mesh, mesh->bounds(), 17), file);
  }
}

/// The structure as the top level over instances (bottoms: brute), and as the bottom level (top: brute).
TEST_P(Conformance, BothLevelsOfInstancing) {
  const AcceleratorInfo& info = find_accelerator(GetParam());
  auto mesh = share(lattice_cubes());
  auto prims = std::make_shared<const TrianglePrims>(mesh);
  std::shared_ptr<Accelerator> base_brute = make_accelerator("brute", prims, Params{});
  base_brute->build();
  std::shared_ptr<Accelerator> base_accel = make_accelerator(GetParam(), prims, Params{});
  base_accel->build();
  auto instances_over = [&](std::shared_ptr<const Accelerator> base) {
    std::vector<Instance> list;
    for (int i = 0; i < 12; ++i) {
      glm::mat4 m(1.0f);
      m = glm::translate(m, vec3(float(i % 4) * 2.5f, float(i / 4) * 3.0f, float(i % 3)));
      m = glm::rotate(m, 0.3f * float(i), glm::normalize(vec3(1, 2, 3)));
      m = glm::scale(m, vec3(1.0f + 0.1f * float(i), 0.5f + 0.05f * float(i), 1.0f));
      if (i == 5) m = glm::translate(glm::mat4(1.0f), vec3(2.5f, 3.0f, 2.0f));  // exact overlap with another
      list.push_back({base, m, glm::inverse(m), 0, {}});
    }
    return std::make_shared<const InstancePrims>(std::move(list));
  };
  auto all_brute = make_instance_accelerator("brute", instances_over(base_brute), Params{});
  all_brute->build();
  const AABB world = all_brute->bounds();
  const std::vector<Ray> rays = adversarial_rays(Mesh{}, world, 19);
  if (info.make_for_instances) {
    auto top = make_instance_accelerator(GetParam(), instances_over(base_brute), Params{});
    top->build();
    expect_same_as_brute(*top, *all_brute, rays, "as top level");
  }
  auto bottom = make_instance_accelerator("brute", instances_over(base_accel), Params{});
  bottom->build();
  expect_same_as_brute(*bottom, *all_brute, rays, "as bottom level");
}

/// Rays derived from brute's hits of `rays`, as a tracer makes secondary rays: from the hit point on
/// (tmin 0, and tmin at the hit's own t), back towards the origin, reflected, and the original ray cut at
/// the hit (tmax = t, tmin = t, both). Their hits lie within rounding of t = 0 or of the interval's ends,
/// where an outside check found every BVH, the octree and the bsp missing hits brute reported (the kernel's
/// rounding put them just outside the triangle's box; kernel_hit_in_box).
std::vector<Ray> rays_from_hits(const Mesh& mesh, const std::vector<Ray>& rays) {
  auto brute = make_accelerator("brute", std::make_shared<const TrianglePrims>(share(mesh)), Params{});
  brute->build();
  std::vector<Hit> hits(rays.size());
  trace_closest(*brute, rays, hits, 1);
  std::vector<Ray> out;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!hits[i].found() || !std::isfinite(hits[i].t)) continue;
    const Ray& r = rays[i];
    const float t = hits[i].t;
    const vec3 p = r.org + t * r.dir;
    const Triangle tri = mesh.triangle(hits[i].prim);
    const vec3 n = glm::cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
    const vec3 bounce =
        glm::dot(n, n) > 0.0f ? r.dir - (2.0f * glm::dot(r.dir, n) / glm::dot(n, n)) * n : -r.dir;
    out.push_back({p, r.dir, 0.0f, kInf});
    out.push_back({p, r.dir, -1e-6f * (1.0f + std::fabs(t)), kInf});
    out.push_back({p, -r.dir, 0.0f, kInf});
    out.push_back({p, bounce, 0.0f, kInf});
    out.push_back({r.org, r.dir, t, kInf});
    out.push_back({r.org, r.dir, r.tmin, t});
    out.push_back({r.org, r.dir, t, t});
    out.push_back({r.org, r.dir, std::nextafter(t, kInf), kInf});
  }
  return out;
}

/// The same mesh far from the origin and far from the rays' origins, and at other scales.
Mesh transformed(const Mesh& mesh, float scale, vec3 offset) {
  Mesh m = mesh;
  for (vec3& v : m.vertices) v = v * scale + offset;
  return m;
}

TEST_P(Conformance, RaysFromHitPointsAndFarOrigins) {
  // The outside check's smallest cases: one triangle hit just outside its box by rounding (and an ordinary
  // hit), and four elongated triangles (4e4-7e5 long, 1e-3 thin) the bsp lost one of.
  check_mesh(GetParam(), share(one_triangle()),
             {{{1.0f, 3.6915807e-08f, 1.1479106e-08f}, {0.34738958f, 0.64651322f, -0.67922097f}, 0.0f, kInf},
              {{1.0f, -6.4549965e-09f, -1.5031716e-08f}, {26.261877f, 522.63513f, 612.48895f}, 0.0f, kInf},
              {{0.25f, 0.25f, 1.0f}, {0.0f, 0.0f, -1.0f}, 0.0f, kInf}},
             "one triangle, hits outside its box by rounding");
  Mesh elongated;
  add_triangle(elongated, {263926.906f, 0.000636331097f, 0.00079860253f},
               {263977.406f, 0.000640983344f, 0.000329054223f},
               {263999.906f, 0.000303342415f, 0.000723590434f});
  add_triangle(elongated, {738445.375f, 0.000668097346f, 6.00855783e-05f},
               {738486.812f, 0.000864975504f, 0.00077214028f}, {738537.0f, 0.000961288693f, 0.000473855122f});
  add_triangle(elongated, {361655.656f, 0.00027731029f, 0.00072183559f},
               {361665.312f, 0.000923310232f, 1.01927099e-05f},
               {361682.781f, 0.000636665092f, 0.000922433392f});
  add_triangle(elongated, {40086.0938f, 9.84208873e-06f, 0.000335646153f},
               {40106.2539f, 0.000490324921f, 0.000251173478f},
               {40162.7969f, 0.000428018859f, 0.000776287867f});
  check_mesh(GetParam(), share(elongated),
             {{{0x1.39647p+15f, 0x1.739418p-13f, 0x1.a2bf1ep-12f},
               {-0x1.c5a76cp-2f, 0x1.5c571ap-3f, 0x1.c2ad4cp-1f},
               0.0f,
               kInf}},
             "elongated triangles");
  const std::filesystem::path dir = std::filesystem::path(ACCELBENCH_SOURCE_DIR) / ".." / "shared" / "meshes";
  Mesh base =
      std::filesystem::exists(dir / "teapot.obj") ? read_mesh((dir / "teapot.obj").string()) : nasty_mix();
  for (const auto& [scale, offset] :
       {std::pair{1.0f, vec3(0.0f)}, std::pair{1e-5f, vec3(0.0f)}, std::pair{1e4f, vec3(0.0f)},
        std::pair{1.0f, vec3(3e4f, -2e4f, 1e4f)},
        std::pair{1.0f, vec3(1e6f, 7e5f, -3e5f)},  // InsertionMargin's coordinate term: 4-8 ulps there
        std::pair{1e20f, vec3(0.0f)}}) {           // areas overflow: the collapse crashed
    const Mesh mesh = transformed(base, scale, offset);
    std::vector<Ray> rays = adversarial_rays(mesh, mesh.bounds(), 23);
    rays.resize(std::min<size_t>(rays.size(), 1200));
    for (size_t k = 0; k < mesh.size(); k += 1 + mesh.size() / 200) {  // from 1e7 away, at a vertex
      const vec3 o = mesh.bounds().center() + vec3(7.7e6f, 5.9e6f, 2.4e6f);
      rays.push_back({o, mesh.triangle(k).v0 - o, 0.0f, kInf});
    }
    std::vector<Ray> derived = rays_from_hits(mesh, rays);
    derived.insert(derived.end(), rays.begin(), rays.end());
    check_mesh(GetParam(), share(mesh), derived, "teapot x " + std::to_string(scale) + ", derived rays");
  }
}

INSTANTIATE_TEST_SUITE_P(Structures, Conformance, ::testing::ValuesIn(structure_names()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string s = info.param;
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

}  // namespace
}  // namespace ab
