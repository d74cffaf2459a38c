// Transform composition order and inverse-transpose normals, on hand-computed cases.
#include "tracer/transform.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "accel/core/error.h"
#include "tracer/scene.h"

namespace ab {
namespace {

void expect_near(const vec3& a, const vec3& b, float tol = 1e-6f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

/// The transform of the only instance of a scene whose instance body is `ops`.
Transform parse_transform(const std::string& ops) {
  const std::string xml =
      "<scene><mesh name='m'><vertices>0 0 0 1 0 0 0 1 0</vertices><triangles>0 1 2</triangles>"
      "</mesh><transform name='x'>" +
      ops + "</transform><instance mesh='m' transform='x'/></scene>";
  return parse_scene(xml, "t.xml", ".").instances.at(0).transform;
}

TEST(Transform, QuarterTurnsFollowTheRightHandRule) {
  expect_near(vec3(rotate_matrix({1, 0, 0}, 90) * glm::vec4(0, 1, 0, 1)), {0, 0, 1}, 0);
  expect_near(vec3(rotate_matrix({0, 1, 0}, 90) * glm::vec4(0, 0, 1, 1)), {1, 0, 0}, 0);
  expect_near(vec3(rotate_matrix({0, 0, 1}, 90) * glm::vec4(1, 0, 0, 1)), {0, 1, 0}, 0);
  expect_near(vec3(rotate_matrix({0, 0, 1}, -90) * glm::vec4(1, 0, 0, 1)), {0, -1, 0}, 0);
  expect_near(vec3(rotate_matrix({0, 1, 0}, 180) * glm::vec4(1, 2, 3, 1)), {-1, 2, -3}, 0);
  expect_near(vec3(rotate_matrix({0, 0, 1}, 450) * glm::vec4(1, 0, 0, 1)), {0, 1, 0}, 0);
}

TEST(Transform, ArbitraryAnglesAndAxes) {
  const float c = std::cos(0.5235987756f), s = std::sin(0.5235987756f);  // 30 degrees
  expect_near(vec3(rotate_matrix({0, 0, 1}, 30) * glm::vec4(1, 0, 0, 1)), {c, s, 0});
  // 120 degrees about (1,1,1) cycles the axes: x -> y -> z.
  expect_near(vec3(rotate_matrix({1, 1, 1}, 120) * glm::vec4(1, 0, 0, 1)), {0, 1, 0}, 1e-6f);
}

TEST(Transform, ElementsComposeInDocumentOrderOnTheFrame) {
  // M = T(1,2,3) * Ry(90) * S(2): (1,0,0) -> scale (2,0,0) -> rotate (0,0,-2) -> translate (1,2,1).
  const Transform x =
      parse_transform("<translate>1 2 3</translate><rotate axis='Y'>90</rotate><scale>2 2 2</scale>");
  expect_near(x.point({1, 0, 0}), {1, 2, 1}, 0);
  expect_near(x.point({0, 0, 0}), {1, 2, 3}, 0);
  // The reverse order: M = S(2) * T(1,0,0): the origin goes to (2,0,0).
  const Transform y = parse_transform("<scale>2</scale><translate>1 0 0</translate>");
  expect_near(y.point({0, 0, 0}), {2, 0, 0}, 0);
  // The lectures' example: T(12,13,14) Rx(90) Ry(120) Rz(10) S(2).
  const Transform z = parse_transform(
      "<translate>12 13 14</translate><rotate axis='X'>90</rotate><rotate axis='Y'>120</rotate>"
      "<rotate axis='Z'>10</rotate><scale>2 2 2</scale>");
  const glm::mat4 m = translate_matrix({12, 13, 14}) * rotate_matrix({1, 0, 0}, 90) *
                      rotate_matrix({0, 1, 0}, 120) * rotate_matrix({0, 0, 1}, 10) * scale_matrix(vec3(2));
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) EXPECT_FLOAT_EQ(z.to_world[c][r], m[c][r]);
  // Hand-computed: (1,0,0) -> S (2,0,0) -> Rz10 (2cos10, 2sin10, 0) -> Ry120 -> Rx90 -> +T.
  const float c10 = std::cos(glm::radians(10.0f)), s10 = std::sin(glm::radians(10.0f));
  const float c120 = -0.5f, s120 = std::sqrt(3.0f) / 2.0f;
  const vec3 a(2 * c10, 2 * s10, 0);
  const vec3 b(c120 * a.x + s120 * a.z, a.y, -s120 * a.x + c120 * a.z);
  const vec3 d(b.x, -b.z, b.y);  // Rx(90): y -> z, z -> -y
  expect_near(z.point({1, 0, 0}), d + vec3(12, 13, 14), 1e-5f);
}

TEST(Transform, InlineElementsFollowTheNamedTransform) {
  const std::string xml =
      "<scene><mesh name='m'><vertices>0 0 0 1 0 0 0 1 0</vertices><triangles>0 1 2</triangles></mesh>"
      "<transform name='up'><translate>0 5 0</translate></transform>"
      "<instance mesh='m' transform='up'><scale>3</scale></instance>"
      "<instance mesh='m'><transform><rotate axis='Z'>90</rotate></transform><translate>1 0 "
      "0</translate></instance>"
      "</scene>";
  const Scene s = parse_scene(xml, "t.xml", ".");
  expect_near(s.instances[0].transform.point({1, 0, 0}), {3, 5, 0}, 0);
  expect_near(s.instances[1].transform.point({0, 0, 0}), {0, 1, 0}, 0);  // Rz90 * T(1,0,0)
}

TEST(Transform, NormalsGoByTheInverseTranspose) {
  // The plane x + y = 1 scaled by (1, 2, 1) becomes x + y/2 = 1, normal (1, 1/2, 0).
  Transform x;
  x.then(scale_matrix({1, 2, 1}));
  ASSERT_TRUE(x.finish());
  const vec3 n = x.normal({1, 1, 0});
  expect_near(n, {1, 0.5f, 0});
  // It stays perpendicular to the transformed triangle's edges.
  const vec3 p0 = x.point({1, 0, 0}), p1 = x.point({0, 1, 0}), p2 = x.point({1, 0, 7});
  EXPECT_NEAR(glm::dot(n, p1 - p0), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::dot(n, p2 - p0), 0.0f, 1e-6f);
  // The plain matrix would not be: (1, 2, 0) is not perpendicular to p1 - p0 = (-1, 2, 0).
  EXPECT_NE(glm::dot(vec3(1, 2, 0), p1 - p0), 0.0f);
  // Under rotation and translation, normals rotate and ignore the translation.
  Transform r;
  r.then(translate_matrix({5, 6, 7}));
  r.then(rotate_matrix({0, 0, 1}, 90));
  ASSERT_TRUE(r.finish());
  expect_near(r.normal({1, 0, 0}), {0, 1, 0}, 1e-6f);
}

TEST(Transform, InverseUndoesTheTransform) {
  const Transform x =
      parse_transform("<translate>1 -2 3</translate><rotate axis='1 2 3'>37</rotate><scale>0.5 4 2</scale>");
  const vec3 p(0.3f, -1.2f, 2.5f);
  expect_near(vec3(x.to_object * glm::vec4(x.point(p), 1.0f)), p, 1e-5f);
}

TEST(Transform, SingularTransformsAreRejectedWithTheLine) {
  Transform x;
  x.then(scale_matrix({1, 0, 1}));
  EXPECT_FALSE(x.finish());
  try {
    parse_transform("\n<scale>1 0 1</scale>");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.xml:1:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("singular"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ab
