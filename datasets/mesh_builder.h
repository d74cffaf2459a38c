// Appending vertices and triangles to a mesh, then trimming it to an exact triangle count.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>

#include "accel/core/mesh.h"

namespace ab {

/// Accumulates a generated mesh. Generators emit at least the target number of triangles and
/// finish() trims the excess from the end, so every generator hits its target exactly.
class MeshBuilder {
 public:
  /// Reserves room for about `triangles` triangles and `vertices` vertices.
  MeshBuilder(uint64_t triangles, uint64_t vertices) {
    mesh_.triangles.reserve(triangles);
    mesh_.vertices.reserve(vertices);
  }
  /// Adds a vertex and returns its index.
  uint32_t vertex(const vec3& p) {
    mesh_.vertices.push_back(p);
    return static_cast<uint32_t>(mesh_.vertices.size() - 1);
  }
  /// Adds a triangle over existing vertices.
  void triangle(uint32_t a, uint32_t b, uint32_t c) { mesh_.triangles.emplace_back(a, b, c); }
  /// Adds a triangle with three new vertices.
  void triangle(const vec3& a, const vec3& b, const vec3& c) {
    const uint32_t i = vertex(a);
    vertex(b);
    vertex(c);
    triangle(i, i + 1, i + 2);
  }
  /// Number of triangles so far.
  uint64_t triangles() const { return mesh_.triangles.size(); }
  /// Keeps the first `target` triangles (when there are more) and drops the vertices past the
  /// last one still referenced.
  Mesh finish(uint64_t target) {
    if (mesh_.triangles.size() > target) mesh_.triangles.resize(target);
    uint32_t used = 0;
    for (const glm::uvec3& t : mesh_.triangles) used = std::max({used, t.x + 1, t.y + 1, t.z + 1});
    mesh_.vertices.resize(std::min<size_t>(mesh_.vertices.size(), used));
    mesh_.vertices.shrink_to_fit();
    mesh_.triangles.shrink_to_fit();
    return std::move(mesh_);
  }

 private:
  Mesh mesh_;
};

}  // namespace ab
