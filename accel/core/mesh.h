// An indexed triangle mesh: the input every structure is built over.
#pragma once

#include <glm/glm.hpp>
#include <vector>

#include "accel/core/triangle.h"

namespace ab {

/// Vertices and triangles (indices into vertices) in file order; triangle i has id i.
/// Degenerate, duplicate and non-manifold triangles are kept so that ids never shift.
struct Mesh {
  std::vector<vec3> vertices;
  std::vector<glm::uvec3> triangles;

  /// Number of triangles.
  size_t size() const { return triangles.size(); }
  /// The vertices of triangle i.
  Triangle triangle(size_t i) const {
    const glm::uvec3& t = triangles[i];
    return {vertices[t.x], vertices[t.y], vertices[t.z]};
  }
  /// Bounds of all vertices referenced by triangles.
  AABB bounds() const {
    AABB b;
    for (size_t i = 0; i < size(); ++i) b.extend(triangle(i).bounds());
    return b;
  }
};

}  // namespace ab
