// Polygon clipping (accel/core/clip.h) against the plain Sutherland and Hodgman (1974) algorithm it
// replaced (a copy of the whole polygon per plane, every plane clipped): the same points, bit for bit, on
// random, degenerate (collinear, zero-area, repeated vertices) and box-grazing triangles.
#include "accel/core/clip.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>

namespace ab {
namespace {

/// The reference: one full Sutherland and Hodgman pass per plane (the code before kd7).
void reference_clip(ClipPolygon& poly, const vec3& normal, float offset) {
  if (poly.n == 0) return;
  ClipPolygon out;
  for (int i = 0; i < poly.n; ++i) {
    const vec3& a = poly.v[i];
    const vec3& b = poly.v[(i + 1) % poly.n];
    const float da = glm::dot(normal, a) - offset;
    const float db = glm::dot(normal, b) - offset;
    if (da <= 0.0f && out.n < static_cast<int>(out.v.size())) out.v[out.n++] = a;
    if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {
      const float s = da / (da - db);
      if (out.n < static_cast<int>(out.v.size())) out.v[out.n++] = a + s * (b - a);
    }
  }
  poly = out;
}

void reference_clip_to_box(ClipPolygon& poly, const AABB& box) {
  for (int a = 0; a < 3 && poly.n > 0; ++a) {
    vec3 axis(0.0f);
    axis[a] = 1.0f;
    reference_clip(poly, axis, box.hi[a]);
    reference_clip(poly, -axis, -box.lo[a]);
  }
}

AABB reference_bounds(const Triangle& tri, const AABB& box) {
  if (!tri.bounds().overlaps(box)) return AABB{};
  ClipPolygon poly;
  poly.v = {tri.v0, tri.v1, tri.v2};
  poly.n = 3;
  reference_clip_to_box(poly, box);
  AABB out;
  for (int i = 0; i < poly.n; ++i) out.extend(poly.v[i]);
  return AABB::intersection(out, box);
}

bool same_bits(const void* a, const void* b, size_t n) {
  return std::memcmp(a, b, n) == 0;
}

void expect_same(const ClipPolygon& got, const ClipPolygon& want) {
  ASSERT_EQ(got.n, want.n);
  EXPECT_TRUE(same_bits(got.v.data(), want.v.data(), sizeof(vec3) * size_t(got.n)));
}

/// The polygon of tri clipped to box, against the reference.
void expect_same_box_clip(const Triangle& tri, const AABB& box) {
  ClipPolygon p;
  p.v = {tri.v0, tri.v1, tri.v2};
  p.n = 3;
  ClipPolygon q = p;
  clip_polygon_to_box(p, box);
  reference_clip_to_box(q, box);
  expect_same(p, q);
}

/// Triangles of every kind: random, collinear, with a repeated vertex, a point, on a box face.
Triangle test_triangle(std::mt19937& rng, const AABB& box) {
  std::uniform_real_distribution<float> u(-1.5f, 1.5f);
  auto p = [&] { return vec3(u(rng), u(rng), u(rng)); };
  const vec3 a = p(), b = p();
  switch (rng() % 6) {
    case 0:
      return {a, b, a + 0.5f * (b - a)};  // collinear
    case 1:
      return {a, a, b};  // repeated vertex
    case 2:
      return {a, a, a};  // a point
    case 3:
      return {vec3(box.hi.x, a.y, a.z), vec3(box.hi.x, b.y, b.z), p()};  // on a face
    case 4:
      return {0.1f * a, 0.1f * b, 0.1f * p()};  // small, often inside
    default:
      return {a, b, p()};
  }
}

TEST(Clip, BoxBoundsEqualTheFullSutherlandHodgman) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int k = 0; k < 20000; ++k) {
    const vec3 c(u(rng), u(rng), u(rng)),
        h(0.05f + std::abs(u(rng)), 0.05f + std::abs(u(rng)), 0.05f + std::abs(u(rng)));
    const AABB box{c - h, c + h};
    const Triangle tri = test_triangle(rng, box);
    const AABB got = clipped_triangle_bounds(tri, box), want = reference_bounds(tri, box);
    ASSERT_EQ(got.empty(), want.empty()) << k;
    if (!want.empty()) {
      EXPECT_TRUE(same_bits(&got, &want, sizeof(AABB))) << k;
    }
    expect_same_box_clip(tri, box);
  }
}

TEST(Clip, ObliquePlanesEqualTheFullSutherlandHodgman) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int k = 0; k < 5000; ++k) {
    const AABB box{vec3(-1.0f), vec3(1.0f)};
    const Triangle tri = test_triangle(rng, box);
    ClipPolygon p;
    p.v = {tri.v0, tri.v1, tri.v2};
    p.n = 3;
    ClipPolygon q = p;
    for (int plane = 0; plane < 12; ++plane) {  // enough planes to fill the capacity on some polygons
      const vec3 n(u(rng), u(rng), u(rng));
      const float offset = 0.5f * u(rng);
      clip_polygon(p, n, offset);
      reference_clip(q, n, offset);
      expect_same(p, q);
    }
  }
}

TEST(Clip, HugeAndNanCoordinatesEqualTheFullSutherlandHodgman) {
  // Coordinates near the float range, where an edge's difference can overflow, and NaN coordinates.
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(-3.0e38f, 3.0e38f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int k = 0; k < 2000; ++k) {
    const AABB box{vec3(-1.0e38f), vec3(1.0e38f)};
    Triangle tri{vec3(u(rng), u(rng), u(rng)), vec3(u(rng), u(rng), u(rng)), vec3(u(rng), u(rng), u(rng))};
    if (k % 4 == 0) tri.v1.y = nan;
    expect_same_box_clip(tri, box);
  }
}

}  // namespace
}  // namespace ab
