#include "tracer/sampling.h"

#include <cmath>
#include <numbers>

namespace ab {

Stratified2D::Stratified2D(uint32_t n, Rng& rng) : n_(n), k_(0), perm_(n), perm_y_(n) {
  const auto k = static_cast<uint32_t>(std::lround(std::sqrt(double(n))));
  if (k * k == n) k_ = k;
  for (uint32_t i = 0; i < n; ++i) perm_[i] = perm_y_[i] = i;
  // Fisher-Yates shuffles: which stratum sample i takes, and (Latin hypercube) its y stratum.
  for (uint32_t i = n; i > 1; --i) std::swap(perm_[i - 1], perm_[rng.below(i)]);
  for (uint32_t i = n; i > 1; --i) std::swap(perm_y_[i - 1], perm_y_[rng.below(i)]);
}

glm::vec2 Stratified2D::get(uint32_t i, Rng& rng) const {
  const uint32_t s = perm_[i % n_];
  const float jx = rng.uniform(), jy = rng.uniform();
  if (k_ > 0) return {(float(s % k_) + jx) / float(k_), (float(s / k_) + jy) / float(k_)};
  return {(float(s) + jx) / float(n_), (float(perm_y_[s]) + jy) / float(n_)};
}

glm::vec2 sample_disk(float u, float v) {
  const float a = 2.0f * u - 1.0f, b = 2.0f * v - 1.0f;
  if (a == 0.0f && b == 0.0f) return {0.0f, 0.0f};
  constexpr float kQuarterPi = std::numbers::pi_v<float> / 4.0f;
  float r, phi;
  if (std::fabs(a) > std::fabs(b)) {
    r = a;
    phi = kQuarterPi * (b / a);
  } else {
    r = b;
    phi = 2.0f * kQuarterPi - kQuarterPi * (a / b);
  }
  return {r * std::cos(phi), r * std::sin(phi)};
}

void orthonormal_basis(const vec3& n, vec3& t, vec3& b) {
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  t = vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  b = vec3(c, sign + n.y * n.y * a, -n.y);
}

vec3 sample_cosine_hemisphere(const vec3& n, float u, float v) {
  const glm::vec2 d = sample_disk(u, v);
  const float z = std::sqrt(std::max(0.0f, 1.0f - d.x * d.x - d.y * d.y));
  vec3 t, b;
  orthonormal_basis(n, t, b);
  return glm::normalize(d.x * t + d.y * b + z * n);
}

vec3 sample_phong_lobe(const vec3& a, float exponent, float u, float v) {
  const float cos_theta = std::pow(1.0f - u, 1.0f / (exponent + 1.0f));
  const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
  const float phi = 2.0f * std::numbers::pi_v<float> * v;
  vec3 t, b;
  orthonormal_basis(a, t, b);
  return glm::normalize(sin_theta * std::cos(phi) * t + sin_theta * std::sin(phi) * b + cos_theta * a);
}

}  // namespace ab
