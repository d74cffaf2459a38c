// Motion blur's one interpolation rule: a ray's time in [0, 1] spans the camera's shutter, sampled at T >= 2
// evenly spaced time steps; between two steps everything moves linearly (Embree's time steps: segment
// floor(time (T - 1)), fraction time (T - 1) - segment). Triangles (motion_prims.h) and instance
// transforms (instances.h) both use these functions, so every structure sees the same geometry at a time.
#pragma once

#include <algorithm>
#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/triangle.h"

namespace ab {

/// Where a time falls among the time steps: between step `index` and `index + 1`, `fraction` of the way.
struct MotionSegment {
  uint32_t index = 0;
  float fraction = 0.0f;
};

/// The segment of time in [0, 1] among `steps` >= 2 time steps (time 1 is the end of the last segment).
inline MotionSegment motion_segment(float time, uint32_t steps) {
  const uint32_t segments = steps - 1;
  const float x = time * float(segments);
  const uint32_t s = x >= float(segments) ? segments - 1 : static_cast<uint32_t>(x);
  return {s, x - float(s)};
}

/// (1 - f) a + f b, clamped to [min(a, b), max(a, b)] so that rounding never leaves the segment's range
/// (the swept bounds hold every interpolated value exactly).
inline float lerp_in_range(float a, float b, float f) {
  const float r = (1.0f - f) * a + f * b;
  return std::clamp(r, std::min(a, b), std::max(a, b));
}

/// lerp_in_range per coordinate.
inline vec3 lerp_in_range(const vec3& a, const vec3& b, float f) {
  return {lerp_in_range(a.x, b.x, f), lerp_in_range(a.y, b.y, f), lerp_in_range(a.z, b.z, f)};
}

/// The triangle moving from a to b over one segment, at fraction f: each vertex interpolated linearly.
inline Triangle lerp_triangle(const Triangle& a, const Triangle& b, float f) {
  return {lerp_in_range(a.v0, b.v0, f), lerp_in_range(a.v1, b.v1, f), lerp_in_range(a.v2, b.v2, f)};
}

/// The matrix at `time` of a transform given at the time steps: entry by entry linear per segment, as
/// Embree interpolates an instance's FLOAT3X4 time steps.
inline glm::mat4 matrix_at(const std::vector<glm::mat4>& steps, float time) {
  const MotionSegment seg = motion_segment(time, static_cast<uint32_t>(steps.size()));
  const glm::mat4& a = steps[seg.index];
  const glm::mat4& b = steps[seg.index + 1];
  glm::mat4 m;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] = lerp_in_range(a[c][r], b[c][r], seg.fraction);
  return m;
}

}  // namespace ab
