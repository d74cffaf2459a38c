#include "tracer/animation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ab {

size_t AnimatedElement::value_count(Kind kind) {
  switch (kind) {
    case Kind::kTranslate:
    case Kind::kScale:
      return 3;
    case Kind::kRotate:
      return 1;
    case Kind::kQuaternion:
      return 4;
    case Kind::kMatrix:
      return 16;
  }
  return 0;
}

bool frame_file_name(const std::string& pattern, uint64_t k, std::string& out) {
  const size_t at = pattern.find('%');
  if (at == std::string::npos || pattern.find('%', at + 1) != std::string::npos) return false;
  size_t i = at + 1;
  int width = 0;
  if (i < pattern.size() && pattern[i] == '0') {
    ++i;
    if (i >= pattern.size() || pattern[i] < '1' || pattern[i] > '9') return false;
    width = pattern[i++] - '0';
  }
  if (i >= pattern.size() || pattern[i] != 'd') return false;
  char digits[32];
  std::snprintf(digits, sizeof digits, "%0*llu", width, static_cast<unsigned long long>(k));
  out = pattern.substr(0, at) + digits + pattern.substr(i + 1);
  return true;
}

glm::vec4 slerp_quaternion(glm::vec4 a, glm::vec4 b, float s) {
  // Shoemake 1985: q(s) = sin((1-s)w)/sin(w) a + sin(s w)/sin(w) b, w the angle between a and b;
  // b is negated when the dot is negative so the interpolation takes the shorter arc.
  float d = glm::dot(a, b);
  if (d < 0.0f) {
    b = -b;
    d = -d;
  }
  if (d > 0.9995f) {
    const glm::vec4 q = a + s * (b - a);
    const float len = glm::length(q);
    return len > 0.0f ? q / len : a;
  }
  const float w = std::acos(std::min(d, 1.0f));
  const float sw = std::sin(w);
  return (std::sin((1.0f - s) * w) / sw) * a + (std::sin(s * w) / sw) * b;
}

glm::mat4 quaternion_matrix(glm::vec4 q) {
  const float len = glm::length(q);
  if (!(len > 0.0f)) return glm::mat4(1.0f);
  q /= len;
  const float x = q.x, y = q.y, z = q.z, w = q.w;
  glm::mat4 m(1.0f);  // column-major: m[col][row]
  m[0][0] = 1 - 2 * (y * y + z * z);
  m[0][1] = 2 * (x * y + z * w);
  m[0][2] = 2 * (x * z - y * w);
  m[1][0] = 2 * (x * y - z * w);
  m[1][1] = 1 - 2 * (x * x + z * z);
  m[1][2] = 2 * (y * z + x * w);
  m[2][0] = 2 * (x * z + y * w);
  m[2][1] = 2 * (y * z - x * w);
  m[2][2] = 1 - 2 * (x * x + y * y);
  return m;
}

std::vector<float> AnimatedElement::values_at(float t) const {
  if (times.size() <= 1 || t <= times.front()) return values.front();
  if (t >= times.back()) return values.back();
  // The key segment [k, k+1] holding t; an exact key time gives that key's values exactly.
  const size_t k = size_t(std::upper_bound(times.begin(), times.end(), t) - times.begin()) - 1;
  if (t == times[k] || interpolation == Interpolation::kStep) return values[k];
  const float s = (t - times[k]) / (times[k + 1] - times[k]);
  const std::vector<float>& a = values[k];
  const std::vector<float>& b = values[k + 1];
  if (kind == Kind::kQuaternion) {
    const glm::vec4 q = slerp_quaternion({a[0], a[1], a[2], a[3]}, {b[0], b[1], b[2], b[3]}, s);
    return {q.x, q.y, q.z, q.w};
  }
  std::vector<float> out(a.size());
  for (size_t i = 0; i < a.size(); ++i) out[i] = a[i] + s * (b[i] - a[i]);
  return out;
}

glm::mat4 AnimatedElement::matrix_at(float t) const {
  const std::vector<float> v = values_at(t);
  switch (kind) {
    case Kind::kTranslate:
      return translate_matrix({v[0], v[1], v[2]});
    case Kind::kRotate:
      return rotate_matrix(axis, v[0]);
    case Kind::kScale:
      return scale_matrix({v[0], v[1], v[2]});
    case Kind::kQuaternion:
      return quaternion_matrix({v[0], v[1], v[2], v[3]});
    case Kind::kMatrix:
      break;
  }
  glm::mat4 m;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] = v[size_t(c * 4 + r)];
  return m;
}

void AnimatedTransform::then(const glm::mat4& m) {
  AnimatedElement e;
  e.kind = AnimatedElement::Kind::kMatrix;
  e.times = {0.0f};
  std::vector<float> v(16);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) v[size_t(c * 4 + r)] = m[c][r];
  e.values = {std::move(v)};
  elements.push_back(std::move(e));
}

void AnimatedTransform::then(const AnimatedTransform& other) {
  elements.insert(elements.end(), other.elements.begin(), other.elements.end());
}

bool AnimatedTransform::animated() const {
  return std::any_of(elements.begin(), elements.end(),
                     [](const AnimatedElement& e) { return e.times.size() > 1; });
}

void AnimatedTransform::time_range(float& first, float& last) const {
  bool any = false;
  for (const AnimatedElement& e : elements) {
    if (e.times.size() <= 1) continue;
    first = any ? std::min(first, e.times.front()) : e.times.front();
    last = any ? std::max(last, e.times.back()) : e.times.back();
    any = true;
  }
  if (!any) first = last = 0.0f;
}

bool AnimatedTransform::evaluate(float t, Transform& out) const {
  out = Transform{};
  for (const AnimatedElement& e : elements) out.then(e.matrix_at(t));
  return out.finish();
}

}  // namespace ab
