#include "tracer/light.h"

#include <cmath>

namespace ab {

vec3 AreaLight::normal_area() const {
  return glm::cross(edge1, edge2);
}

float AreaLight::intersect(const Ray& ray) const {
  const vec3 n = normal_area();
  const float den = glm::dot(ray.dir, n);
  if (den == 0.0f) return kInf;
  const float t = glm::dot(corner - ray.org, n) / den;
  if (!(t > ray.tmin && t < ray.tmax)) return kInf;
  const vec3 d = ray.org + t * ray.dir - corner;
  const float s = glm::dot(d, edge1) / glm::dot(edge1, edge1);
  const float r = glm::dot(d, edge2) / glm::dot(edge2, edge2);
  return (s >= 0.0f && s <= 1.0f && r >= 0.0f && r <= 1.0f) ? t : kInf;
}

}  // namespace ab
