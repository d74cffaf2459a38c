#include "accel/reference/peer.h"

#include <cmath>

namespace ab {

double peer_distance(const Ray& ray, const glm::dvec3& p) {
  const glm::dvec3 d(ray.dir), o(ray.org), a = glm::abs(d);
  const int axis = a.x >= a.y && a.x >= a.z ? 0 : a.y >= a.z ? 1 : 2;
  return (p[axis] - o[axis]) / d[axis];
}

glm::dvec2 peer_barycentrics(const Triangle& tri, const glm::dvec3& p) {
  const glm::dvec3 a(tri.v0), e1 = glm::dvec3(tri.v1) - a, e2 = glm::dvec3(tri.v2) - a, ap = p - a;
  const glm::dvec3 n = glm::cross(e1, e2);
  const double nn = glm::dot(n, n);
  if (nn == 0.0) return glm::dvec2(0.0);
  // p = a + u e1 + v e2, so ap x e2 = u n and e1 x ap = v n.
  return glm::dvec2(glm::dot(glm::cross(ap, e2), n) / nn, glm::dot(glm::cross(e1, ap), n) / nn);
}

Hit peer_hit(const Ray& ray, const Triangle& tri, uint32_t prim, uint32_t inst, const glm::dvec3& p) {
  TriangleHit th;
  if (intersect_triangle(ray, tri, th)) return {th.t, prim, inst, th.u, th.v};
  float t = static_cast<float>(peer_distance(ray, p));
  if (!(t >= ray.tmin)) t = ray.tmin;  // rounding below the start point (or NaN)
  if (!(t <= ray.tmax)) return Hit{};
  const glm::dvec2 uv = peer_barycentrics(tri, p);
  return {t + 0.0f, prim, inst, static_cast<float>(uv.x), static_cast<float>(uv.y)};  // -0 becomes +0
}

}  // namespace ab
