#include "harness/compare.h"

#include <cmath>
#include <cstring>

namespace ab {

IdenticalResult compare_identical(std::span<const Hit> expected, std::span<const Hit> actual) {
  IdenticalResult r;
  r.compared = std::min(expected.size(), actual.size());
  if (expected.size() != actual.size()) r.differing += std::max(expected.size(), actual.size()) - r.compared;
  for (size_t i = 0; i < r.compared; ++i) {
    if (std::memcmp(&expected[i], &actual[i], sizeof(Hit)) != 0) {
      ++r.differing;
      if (r.first_differences.size() < 10) r.first_differences.push_back(i);
    }
  }
  return r;
}

namespace {

constexpr float kTieTolerance = 1e-4f;
constexpr float kEdgeTolerance = 1e-4f;
constexpr float kEdgeDistance = 1e-5f;
constexpr float kGrazeCosine = 1e-3f;

bool close_t(float a, float b) {
  return std::fabs(a - b) <= kTieTolerance * std::max({1.0f, std::fabs(a), std::fabs(b)});
}

/// Largest absolute coordinate of the triangle's vertices and the ray's origin (the scale of the kernel's
/// rounding).
float coordinate_scale(const Ray& ray, const Triangle& tri) {
  float s = 0.0f;
  for (const vec3& p : {ray.org, tri.v0, tri.v1, tri.v2})
    for (int a = 0; a < 3; ++a) s = std::max(s, std::fabs(p[a]));
  return s;
}

/// True when the hit lies within 1e-4 (barycentric) of an edge, or within 1e-5 of the coordinates' scale
/// (in distance) of one: on a sliver a barycentric coordinate is the distance to the long edge divided by
/// a tiny height, so float rounding of about 1e-7 of the scale moves it by far more than 1e-4.
bool near_edge(const Ray& ray, const Hit& h, const HitTriangleAtFn& triangle_of) {
  if (!h.found()) return false;
  const float w = 1.0f - h.u - h.v;
  if (h.u <= kEdgeTolerance || h.v <= kEdgeTolerance || w <= kEdgeTolerance) return true;
  const Triangle tri = triangle_of(h, ray.time);
  const float twice_area = glm::length(glm::cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
  const float opposite[3] = {glm::length(tri.v2 - tri.v1), glm::length(tri.v0 - tri.v2),
                             glm::length(tri.v1 - tri.v0)};
  const float weight[3] = {w, h.u, h.v};
  const float tolerance = kEdgeDistance * coordinate_scale(ray, tri);
  for (int k = 0; k < 3; ++k)
    if (opposite[k] > 0.0f && std::fabs(weight[k]) * twice_area / opposite[k] <= tolerance) return true;
  return false;
}

/// True when the ray meets the hit's triangle at a grazing angle (cosine below 1e-3), or so flat that the
/// one kernel calls it parallel (its rounding bound on the denominator: on slivers that reaches cosines of
/// a few 1e-2, where Embree's kernel still reports a hit).
bool grazing(const Ray& ray, const Hit& h, const HitTriangleAtFn& triangle_of) {
  if (!h.found()) return false;
  const Triangle tri = triangle_of(h, ray.time);
  const vec3 n = glm::cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
  const float ln = glm::length(n) * glm::length(ray.dir);
  return ln == 0.0f || std::fabs(glm::dot(n, ray.dir)) / ln < kGrazeCosine || kernel_calls_parallel(ray, tri);
}

bool near_limit(const Ray& ray, const Hit& h) {
  return h.found() && (close_t(h.t, ray.tmin) || (std::isfinite(ray.tmax) && close_t(h.t, ray.tmax)));
}

}  // namespace

Agreement classify_agreement(std::span<const Ray> rays, std::span<const Hit> ours,
                             std::span<const Hit> theirs, const HitTriangleAtFn& triangle_of) {
  Agreement a;
  for (size_t i = 0; i < rays.size(); ++i) {
    const Hit& x = ours[i];
    const Hit& y = theirs[i];
    if (!x.found() && !y.found()) {
      ++a.agree;
    } else if (x.found() && y.found() && x.prim == y.prim && x.inst == y.inst && close_t(x.t, y.t)) {
      ++a.agree;
    } else if (x.found() && y.found() && close_t(x.t, y.t)) {
      ++a.tie;
    } else if (near_edge(rays[i], x, triangle_of) || near_edge(rays[i], y, triangle_of)) {
      ++a.edge;
    } else if (grazing(rays[i], x, triangle_of) || grazing(rays[i], y, triangle_of)) {
      ++a.graze;
    } else if (near_limit(rays[i], x) || near_limit(rays[i], y)) {
      ++a.limit;
    } else {
      ++a.unexplained;
      if (a.unexplained_rays.size() < 10) a.unexplained_rays.push_back(i);
    }
  }
  return a;
}

nlohmann::json to_json(const IdenticalResult& r) {
  return {{"compared", r.compared},
          {"differing", r.differing},
          {"identical", r.identical()},
          {"first_differences", r.first_differences}};
}

nlohmann::json to_json(const Agreement& a) {
  return {{"agree", a.agree},
          {"tie", a.tie},
          {"edge", a.edge},
          {"graze", a.graze},
          {"limit", a.limit},
          {"unexplained", a.unexplained},
          {"unexplained_rays", a.unexplained_rays}};
}

Agreement classify_agreement(std::span<const Ray> rays, std::span<const Hit> ours,
                             std::span<const Hit> theirs, const HitTriangleFn& triangle_of) {
  return classify_agreement(rays, ours, theirs,
                            HitTriangleAtFn([&](const Hit& h, float) { return triangle_of(h); }));
}

}  // namespace ab
