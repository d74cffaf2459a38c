// Ray and Hit, the records of the .rays and .hits files, and the one acceptance rule every structure uses.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <limits>

namespace ab {

using glm::vec3;

/// Positive infinity in single precision.
inline constexpr float kInf = std::numeric_limits<float>::infinity();
/// The id of "no triangle" and "no instance" in hits (contract: 0xFFFFFFFF).
inline constexpr uint32_t kInvalidId = 0xFFFFFFFFu;

/// A ray: origin, direction (not necessarily normalized, may have zero components), and the
/// parametric interval [tmin, tmax] in units of that direction, and a time in [0, 1] within the camera's
/// shutter (motion blur; 0 for rays of a static scene). Layout matches the ABRAYS02 record (ABRAYS01
/// records are its first 32 bytes).
struct Ray {
  vec3 org{0.0f};
  vec3 dir{0.0f, 0.0f, 1.0f};
  float tmin = 0.0f;
  float tmax = kInf;
  float time = 0.0f;
};
static_assert(sizeof(Ray) == 36);

/// The closest hit of a ray. Layout matches the .hits record. A miss has t = +inf and invalid ids.
struct Hit {
  float t = kInf;
  uint32_t prim = kInvalidId;
  uint32_t inst = kInvalidId;
  float u = 0.0f;
  float v = 0.0f;

  /// True when the record describes a hit.
  bool found() const { return prim != kInvalidId; }
};
static_assert(sizeof(Hit) == 20);

/// The one acceptance rule every structure uses: a candidate replaces the best when it is
/// strictly closer, or equally close with a lower (inst, prim) pair.
inline bool is_better_hit(float t, uint32_t inst, uint32_t prim, const Hit& best) {
  if (t != best.t) return t < best.t;
  if (inst != best.inst) return inst < best.inst;
  return prim < best.prim;
}

}  // namespace ab
