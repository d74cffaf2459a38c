// Animated transforms: a sequence of transform elements (translate, rotate, scale, quaternion rotation,
// matrix), each with its own keyframes, composed in order exactly as a static transform is
// (tracer/transform.h: M = M1 * M2 * ... * Mn). XML keyframes give every element the same key times;
// glTF node channels give each of T, R, S its own. One function evaluates the transform at a time:
// the frame selector, and later motion blur, call it.
#pragma once

#include <string>
#include <vector>

#include "tracer/transform.h"

namespace ab {

/// How values between two keys are found.
enum class Interpolation {
  kLinear,  ///< linear in the element's values (angles as angles; quaternions by slerp)
  kStep,    ///< the value of the key at or before the time
};

/// One element of an animated transform with its keys (times strictly increasing, values per key).
struct AnimatedElement {
  /// What the values mean.
  enum class Kind {
    kTranslate,   ///< 3 values: x y z
    kRotate,      ///< 1 value: degrees about `axis`
    kScale,       ///< 3 values: sx sy sz
    kQuaternion,  ///< 4 values: x y z w (glTF order), normalized when composed
    kMatrix,      ///< 16 values, column-major (interpolated entry by entry)
  };
  Kind kind = Kind::kTranslate;
  vec3 axis{0.0f, 1.0f, 0.0f};  ///< rotation axis (kRotate), non-zero
  Interpolation interpolation = Interpolation::kLinear;
  std::vector<float> times;                ///< key times (one key: a constant element)
  std::vector<std::vector<float>> values;  ///< values[k]: the element's values at times[k]

  /// Values per key of a kind (3, 1, 3, 4 or 16).
  static size_t value_count(Kind kind);
  /// The element's values at time t (clamped to the first and last key).
  std::vector<float> values_at(float t) const;
  /// The element's matrix at time t.
  glm::mat4 matrix_at(float t) const;
};

/// A transform whose elements may move: evaluated at a time, it is a static Transform.
struct AnimatedTransform {
  std::vector<AnimatedElement> elements;  ///< in composition order

  /// Appends a constant matrix (a static element).
  void then(const glm::mat4& m);
  /// Appends all elements of `other` after this one's (M = M_this * M_other).
  void then(const AnimatedTransform& other);
  /// True when some element has more than one key.
  bool animated() const;
  /// The first and last key time over all elements (0, 0 when static).
  void time_range(float& first, float& last) const;
  /// The transform at time t (in the keys' own units). Returns false when the matrix is singular or
  /// not finite at t.
  bool evaluate(float t, Transform& out) const;
};

/// The file name of frame k of a sequence: `pattern` with its one %d or %0Nd (N in 1..9) replaced by k.
/// Returns false when the pattern has no such conversion, more than one, or any other %.
bool frame_file_name(const std::string& pattern, uint64_t k, std::string& out);

/// Spherical linear interpolation of unit quaternions (x, y, z, w) by the shorter arc (Shoemake 1985,
/// "Animating rotation with quaternion curves"); falls back to normalized lerp when nearly parallel.
glm::vec4 slerp_quaternion(glm::vec4 a, glm::vec4 b, float s);
/// The rotation matrix of a quaternion (x, y, z, w), normalized first (identity when zero).
glm::mat4 quaternion_matrix(glm::vec4 q);

}  // namespace ab
