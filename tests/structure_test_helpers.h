// Small inline meshes, ray sets and a brute-force comparison for the structure tests (bvh, grid).
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "accel/core/instances.h"
#include "accel/core/mesh.h"
#include "accel/core/primitives.h"
#include "accel/core/registry.h"
#include "accel/reference/brute.h"

namespace ab::testing {

/// Uniform float in [lo, hi) from a 32-bit generator (portable: no std distributions).
inline float uniform(std::mt19937& rng, float lo, float hi) {
  return lo + (hi - lo) * float(rng() >> 8) * 0x1p-24f;
}

/// Random triangle soup: n triangles of size about `size` in the unit cube.
inline Mesh random_soup(size_t n, uint32_t seed, float size = 0.05f) {
  std::mt19937 rng(seed);
  Mesh m;
  for (size_t i = 0; i < n; ++i) {
    const vec3 c(uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1));
    for (int k = 0; k < 3; ++k)
      m.vertices.push_back(
          c + vec3(uniform(rng, -size, size), uniform(rng, -size, size), uniform(rng, -size, size)));
    m.triangles.push_back({uint32_t(3 * i), uint32_t(3 * i + 1), uint32_t(3 * i + 2)});
  }
  return m;
}

/// A flat, axis-aligned k x k grid of quads (two triangles each) in the plane z = 0 sharing vertices,
/// plus duplicates of a few triangles, a degenerate (collinear) triangle, a point triangle and a
/// triangle lying exactly on the plane x = 0.5 (perpendicular to the others).
inline Mesh adversarial_mesh(int k) {
  Mesh m;
  for (int y = 0; y <= k; ++y)
    for (int x = 0; x <= k; ++x) m.vertices.push_back({float(x) / float(k), float(y) / float(k), 0.0f});
  auto v = [k](int x, int y) { return uint32_t(y * (k + 1) + x); };
  for (int y = 0; y < k; ++y)
    for (int x = 0; x < k; ++x) {
      m.triangles.push_back({v(x, y), v(x + 1, y), v(x + 1, y + 1)});
      m.triangles.push_back({v(x, y), v(x + 1, y + 1), v(x, y + 1)});
    }
  for (int d = 0; d < 3; ++d) m.triangles.push_back(m.triangles[size_t(d * 7) % m.triangles.size()]);
  m.triangles.push_back({v(0, 0), v(1, 1), v(2, 2)});  // collinear
  m.triangles.push_back({v(1, 0), v(1, 0), v(1, 0)});  // point
  const uint32_t base = uint32_t(m.vertices.size());
  m.vertices.push_back({0.5f, 0.1f, -0.5f});
  m.vertices.push_back({0.5f, 0.9f, -0.5f});
  m.vertices.push_back({0.5f, 0.5f, 0.5f});
  m.triangles.push_back({base, base + 1, base + 2});
  return m;
}

/// Rays of every adversarial kind over bounds b: random origins and directions, axis-parallel rays
/// (zero direction components) through vertices and edges, rays starting on triangles, tmin/tmax limits.
inline std::vector<Ray> adversarial_rays(const Mesh& mesh, size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  AABB b = mesh.bounds();
  if (b.empty()) b = {{0, 0, 0}, {1, 1, 1}};
  const vec3 lo = b.lo - 0.2f * (b.extent() + vec3(0.1f)), hi = b.hi + 0.2f * (b.extent() + vec3(0.1f));
  std::vector<Ray> rays;
  for (size_t i = 0; i < count; ++i) {
    Ray r;
    r.org = {uniform(rng, lo.x, hi.x), uniform(rng, lo.y, hi.y), uniform(rng, lo.z, hi.z)};
    r.dir = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
    switch (i % 7) {
      case 1:  // axis-parallel, through a vertex or edge of the mesh
        if (!mesh.vertices.empty()) {
          const vec3 p = mesh.vertices[rng() % mesh.vertices.size()];
          const int a = int(rng() % 3);
          r.org = p;
          r.org[a] = (rng() & 1) ? hi[a] : lo[a];
          r.dir = vec3(0.0f);
          r.dir[a] = r.org[a] == hi[a] ? -1.0f : 1.0f;
        }
        break;
      case 2:  // one zero component, aimed at a triangle's centroid
        if (mesh.size()) {
          const Triangle t = mesh.triangle(rng() % mesh.size());
          r.dir = t.centroid() - r.org;
          r.dir[rng() % 3] = 0.0f;
        }
        break;
      case 3:  // starts on a triangle
        if (mesh.size()) {
          const Triangle t = mesh.triangle(rng() % mesh.size());
          r.org = t.centroid();
        }
        break;
      case 4:  // limited interval, possibly negative tmin
        r.tmin = uniform(rng, -0.5f, 0.5f);
        r.tmax = r.tmin + uniform(rng, 0.0f, 1.5f);
        if (mesh.size()) r.dir = mesh.triangle(rng() % mesh.size()).centroid() - r.org;
        break;
      case 5:  // aimed at a vertex (ties between the triangles sharing it)
        if (!mesh.vertices.empty()) r.dir = mesh.vertices[rng() % mesh.vertices.size()] - r.org;
        break;
      case 6:  // starts exactly at a vertex: every triangle sharing it is hit at t = 0 (ties by id)
        if (!mesh.vertices.empty()) r.org = mesh.vertices[rng() % mesh.vertices.size()];
        break;
      default:
        break;
    }
    rays.push_back(r);
  }
  return rays;
}

/// Builds accel and brute (over the same primitives) and compares hits (byte for byte), occlusion and the
/// counting pass's hits. Returns the number of differences.
inline size_t differences_from_brute(Accelerator& accel, Accelerator& brute, const std::vector<Ray>& rays) {
  accel.build();
  brute.build();
  std::vector<Hit> expected(rays.size()), got(rays.size());
  std::vector<uint8_t> expected_occ(rays.size()), got_occ(rays.size());
  brute.intersect(rays, expected);
  accel.intersect(rays, got);
  brute.occluded(rays, expected_occ);
  accel.occluded(rays, got_occ);
  size_t diff = 0;
  for (size_t i = 0; i < rays.size(); ++i)
    if (std::memcmp(&expected[i], &got[i], sizeof(Hit)) != 0 || expected_occ[i] != got_occ[i]) ++diff;
  // The counting pass must give the same hits.
  RayCounters counters;
  accel.intersect_counted(rays, got, counters);
  for (size_t i = 0; i < rays.size(); ++i)
    if (std::memcmp(&expected[i], &got[i], sizeof(Hit)) != 0) ++diff;
  return diff;
}

/// Builds accelerator `name` over the mesh with params and checks hits (byte for byte) and occlusion
/// against brute force. Returns the number of differing rays.
inline size_t count_differences(const std::string& name, const Mesh& mesh, const std::vector<Ray>& rays,
                                std::map<std::string, std::string> params = {}) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(mesh));
  auto accel = make_accelerator(name, prims, Params(std::move(params)));
  auto brute = make_accelerator("brute", prims, Params());
  return differences_from_brute(*accel, *brute, rays);
}

/// A scene of `copies` transformed instances of one base mesh built with `base_name`, returned as the
/// instance set (for top-level tests).
inline std::shared_ptr<const InstancePrims> make_instances(const Mesh& mesh, const std::string& base_name,
                                                           int copies) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(mesh));
  std::shared_ptr<Accelerator> base = make_accelerator(base_name, prims, Params());
  base->build();
  std::vector<Instance> instances;
  for (int i = 0; i < copies; ++i) {
    Instance inst;
    inst.base = base;
    const float s = 0.5f + 0.25f * float(i % 3);
    inst.to_world = glm::mat4(s);
    inst.to_world[3] = glm::vec4(0.3f * float(i), 0.2f * float(i % 2), 0.1f * float(i % 4), 1.0f);
    inst.to_object = glm::inverse(inst.to_world);
    instances.push_back(inst);
  }
  return std::make_shared<const InstancePrims>(std::move(instances));
}

/// Top-level accelerator `name` over instances vs brute over the same instances (hits, occlusion, the
/// counting pass); number of differences.
inline size_t count_instance_differences(const std::string& name, std::shared_ptr<const InstancePrims> inst,
                                         const std::vector<Ray>& rays) {
  auto accel = make_instance_accelerator(name, inst, Params());
  auto brute = make_instance_accelerator("brute", inst, Params());
  return differences_from_brute(*accel, *brute, rays);
}

}  // namespace ab::testing

namespace ab::testing {
/// Params from a key -> value map (avoids the ambiguity of brace-initializing Params directly).
inline Params make_params(std::map<std::string, std::string> values) {
  return Params(std::move(values));
}

/// Creates and builds accelerator `name` over the mesh with params.
inline std::unique_ptr<Accelerator> built_accelerator(const std::string& name, const Mesh& mesh,
                                                      std::map<std::string, std::string> params = {}) {
  auto prims = std::make_shared<const TrianglePrims>(std::make_shared<const Mesh>(mesh));
  auto accel = make_accelerator(name, prims, Params(std::move(params)));
  accel->build();
  return accel;
}
}  // namespace ab::testing
