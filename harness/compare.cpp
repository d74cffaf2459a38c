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

/// True when hits x and y name the same triangle at t's apart by at most the first-order rounding bound of
/// two kernels computing t = dot(v0 - org, n) / dot(dir, n) with n = e1 x e2 in floats (ours and Embree's
/// Moller-Trumbore are of this form). Each component of n carries an error of at most about 3u |e1| |e2|
/// (the edges' subtractions, the products and their difference; u = 2^-24), so |dn| <= 6u |e1| |e2|. The
/// same n in both dot products cancels its error along the ray, leaving dot(v0 - p, dn) / den, p the hit
/// point (v0 - p = u e1 + v e2): a relative error of 6u |e1| |e2| |u e1 + v e2| / (t |den|), plus 3u of each
/// dot product's terms (Higham 2002, 3.1) and the division's u. Large when |n| is small against |e1| |e2|
/// (a sliver) and the ray oblique: on 200k `needles` (aspect 5000, cosine 0.11) Embree's t and ours differ
/// by 8.5e-4 of t, within the bound of 6.6e-2. Twice the bound for the difference of two kernels.
bool within_rounding(const Ray& ray, const Hit& x, const Hit& y, const HitTriangleAtFn& triangle_of) {
  if (!(x.found() && y.found() && x.prim == y.prim && x.inst == y.inst)) return false;
  const Triangle tri = triangle_of(x, ray.time);
  const glm::dvec3 e1 = glm::dvec3(tri.v1 - tri.v0), e2 = glm::dvec3(tri.v2 - tri.v0);
  const glm::dvec3 n = glm::cross(e1, e2), dir(ray.dir), to_v0 = glm::dvec3(tri.v0) - glm::dvec3(ray.org);
  const double den = std::fabs(glm::dot(dir, n)), num = std::fabs(glm::dot(to_v0, n));
  const double t = std::min(std::fabs(double(x.t)), std::fabs(double(y.t)));
  if (!(den > 0.0 && num > 0.0 && t > 0.0)) return false;
  double lever = 0.0;  // |v0 - p|, the larger of the two hits' points
  for (const Hit* h : {&x, &y}) lever = std::max(lever, glm::length(double(h->u) * e1 + double(h->v) * e2));
  const double ln = glm::length(n);
  const double sliver = 6.0 * glm::length(e1) * glm::length(e2) * lever / (t * den);
  const double one =
      0x1p-24 * (sliver + 3.0 * glm::length(dir) * ln / den + 3.0 * glm::length(to_v0) * ln / num + 1.0);
  return std::fabs(double(x.t) - double(y.t)) <=
         2.0 * one * std::max(std::fabs(double(x.t)), std::fabs(double(y.t)));
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
    } else if (within_rounding(rays[i], x, y, triangle_of)) {
      ++a.rounding;
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
          {"rounding", a.rounding},
          {"unexplained", a.unexplained},
          {"unexplained_rays", a.unexplained_rays}};
}

Agreement classify_agreement(std::span<const Ray> rays, std::span<const Hit> ours,
                             std::span<const Hit> theirs, const HitTriangleFn& triangle_of) {
  return classify_agreement(rays, ours, theirs,
                            HitTriangleAtFn([&](const Hit& h, float) { return triangle_of(h); }));
}

}  // namespace ab
