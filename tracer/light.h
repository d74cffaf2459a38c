// Lights of the tracer: points and rectangles (area lights, sampled for soft shadows).
#pragma once

#include "accel/core/aabb.h"

namespace ab {

/// A point light: radiant intensity, falling off with the squared distance.
struct PointLight {
  vec3 position{0.0f};
  vec3 intensity{1.0f};
};

/// A one-sided rectangular emitter: corner + s * edge1 + t * edge2 for s, t in [0,1]. It emits on the
/// side of edge1 x edge2 with constant radiance.
struct AreaLight {
  vec3 corner{0.0f};
  vec3 edge1{1.0f, 0.0f, 0.0f};
  vec3 edge2{0.0f, 0.0f, 1.0f};
  vec3 radiance{1.0f};

  /// The point at (s, t) in [0,1]^2.
  vec3 point(float s, float t) const { return corner + s * edge1 + t * edge2; }
  /// Unnormalized normal edge1 x edge2 (its length is the area).
  vec3 normal_area() const;
  /// Distance along the ray to the rectangle in (tmin, tmax), or +inf (either side is hit).
  float intersect(const Ray& ray) const;
};

}  // namespace ab
