#include "tracer/transform.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace ab {

glm::mat4 translate_matrix(const vec3& t) {
  return glm::translate(glm::mat4(1.0f), t);
}

glm::mat4 rotate_matrix(const vec3& axis, float degrees) {
  // Rotations by multiples of 90 degrees are built exactly (no cos(pi/2) = -4e-8 residue), so
  // axis-aligned instances stay axis-aligned and hand-computed tests are exact.
  const float turns = degrees / 90.0f;
  const bool quarter = std::fabs(turns) < 1e6f && std::nearbyint(turns) == turns;
  const vec3 a = glm::normalize(axis);
  if (!quarter) return glm::rotate(glm::mat4(1.0f), glm::radians(degrees), a);
  const int q = ((static_cast<int>(turns) % 4) + 4) % 4;
  const float c = q == 0 ? 1.0f : (q == 2 ? -1.0f : 0.0f);
  const float s = q == 1 ? 1.0f : (q == 3 ? -1.0f : 0.0f);
  // Rodrigues: R = c I + s [a]x + (1 - c) a a^T (column-major).
  glm::mat4 r(1.0f);
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) r[col][row] = (1.0f - c) * a[row] * a[col] + (row == col ? c : 0.0f);
  r[1][0] -= s * a.z;
  r[2][0] += s * a.y;
  r[0][1] += s * a.z;
  r[2][1] -= s * a.x;
  r[0][2] -= s * a.y;
  r[1][2] += s * a.x;
  return r;
}

glm::mat4 scale_matrix(const vec3& s) {
  return glm::scale(glm::mat4(1.0f), s);
}

void Transform::then(const glm::mat4& m) {
  to_world = to_world * m;
}

bool Transform::finish() {
  const float det = glm::determinant(to_world);
  if (!(std::isfinite(det)) || det == 0.0f) return false;
  to_object = glm::inverse(to_world);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(to_object[c][r])) return false;
  return true;
}

}  // namespace ab
