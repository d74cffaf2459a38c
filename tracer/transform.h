// Scene transforms: translate, rotate and scale elements composed in document order.
//
// Composition rule (documented in docs/scenes.md): the elements of a <transform> are applied in
// document order to the object's coordinate frame, like successive OpenGL glTranslate / glRotate /
// glScale calls. The composed object-to-world matrix is M = M1 * M2 * ... * Mn, so a point p goes to
// M1(M2(...Mn(p))): the LAST element acts on the object's points first. For
// <translate>t</translate><rotate axis="Y">90</rotate><scale>2 2 2</scale> a vertex is scaled by 2,
// then rotated by 90 degrees about Y, then translated by t.
#pragma once

#include <glm/glm.hpp>

#include "accel/core/aabb.h"

namespace ab {

/// Translation by t.
glm::mat4 translate_matrix(const vec3& t);
/// Right-handed rotation by `degrees` about `axis` (counter-clockwise when the axis points at the
/// viewer); the axis need not be normalized but must be non-zero.
glm::mat4 rotate_matrix(const vec3& axis, float degrees);
/// Scaling by s along the object's axes.
glm::mat4 scale_matrix(const vec3& s);

/// An object-to-world transform with its inverse (for rays) and the inverse transpose (for normals).
struct Transform {
  glm::mat4 to_world{1.0f};
  glm::mat4 to_object{1.0f};

  /// Appends an element in document order: to_world = to_world * m.
  void then(const glm::mat4& m);
  /// Recomputes to_object from to_world; returns false when to_world is singular (or not finite).
  bool finish();
  /// World-space point of an object-space point.
  vec3 point(const vec3& p) const { return vec3(to_world * glm::vec4(p, 1.0f)); }
  /// World-space normal of an object-space normal (inverse transpose; not normalized).
  vec3 normal(const vec3& n) const { return normal_to_world(to_object, n); }

  /// The inverse transpose applied to n, given the world-to-object matrix: (M^-1)^T n.
  static vec3 normal_to_world(const glm::mat4& to_object, const vec3& n) {
    return glm::transpose(glm::mat3(to_object)) * n;
  }
};

}  // namespace ab
