#include "tracer/deform.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ab {

namespace {

/// A value in [0, 1) from a triangle id (splitmix64 finalizer; Steele, Lea and Flood 2014).
float unit_hash(uint64_t id) {
  uint64_t z = id + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return float(z >> 40) / float(1ull << 24);
}

float diagonal(const Mesh& m) {
  const float d = glm::length(m.bounds().extent());
  return d > 0.0f ? d : 1.0f;
}

Mesh wave(const Mesh& base, const Deformer& d, float p) {
  Mesh out = base;
  const float diag = diagonal(base);
  const float amplitude = d.amplitude * diag, wavelength = d.wavelength * diag;
  const float two_pi = 2.0f * std::numbers::pi_v<float>;
  for (vec3& v : out.vertices)
    v += amplitude * std::sin(two_pi * (glm::dot(v, d.direction) / wavelength - d.cycles * p)) * d.axis;
  return out;
}

/// Rotation about the axis through the bounds' centre, the angle growing with the height along the axis
/// (Barr 1984, "Global and local deformations of solid primitives": the twist).
Mesh twist(const Mesh& base, const Deformer& d, float p) {
  Mesh out = base;
  const AABB b = base.bounds();
  if (b.empty()) return out;
  const vec3 c = b.center(), k = d.axis;
  float lo = std::numeric_limits<float>::max(), hi = -lo;
  for (const vec3& v : base.vertices) {
    lo = std::min(lo, glm::dot(v - c, k));
    hi = std::max(hi, glm::dot(v - c, k));
  }
  const float span = hi > lo ? hi - lo : 1.0f;
  const float radians = d.degrees * p * std::numbers::pi_v<float> / 180.0f;
  for (vec3& v : out.vertices) {
    const vec3 r = v - c;
    const float a = radians * (glm::dot(r, k) - lo) / span;
    if (a == 0.0f) continue;  // untwisted vertices keep their bits
    const float cs = std::cos(a), sn = std::sin(a);
    // Rodrigues' rotation formula.
    v = c + r * cs + glm::cross(k, r) * sn + k * glm::dot(k, r) * (1.0f - cs);
  }
  return out;
}

/// Every triangle gets its own three vertices and flies along its unit normal; degenerate triangles
/// (no normal) stay. Triangle i keeps id i.
Mesh explode(const Mesh& base, const Deformer& d, float p) {
  Mesh out;
  out.vertices.reserve(base.size() * 3);
  out.triangles.reserve(base.size());
  const float flight = d.distance * diagonal(base) * p;
  for (size_t i = 0; i < base.size(); ++i) {
    const Triangle t = base.triangle(i);
    const vec3 n = glm::cross(t.v1 - t.v0, t.v2 - t.v0);
    const float len = glm::length(n);
    const vec3 offset =
        len > 0.0f && std::isfinite(len) ? n * (flight * (0.5f + unit_hash(i)) / len) : vec3(0.0f);
    const auto first = static_cast<uint32_t>(out.vertices.size());
    out.vertices.push_back(t.v0 + offset);
    out.vertices.push_back(t.v1 + offset);
    out.vertices.push_back(t.v2 + offset);
    out.triangles.emplace_back(first, first + 1, first + 2);
  }
  return out;
}

}  // namespace

float Deformer::phase(float t) const {
  if (!(end > start)) return t >= end ? 1.0f : 0.0f;
  return std::clamp((t - start) / (end - start), 0.0f, 1.0f);
}

Mesh Deformer::apply(const Mesh& base, float t) const {
  const float p = phase(t);
  switch (kind) {
    case Kind::kWave:
      return wave(base, *this, p);
    case Kind::kTwist:
      return twist(base, *this, p);
    case Kind::kExplode:
      return explode(base, *this, p);
  }
  return base;
}

void MeshAnimation::time_range(float& first, float& last) const {
  if (kind == Kind::kDeformer) {
    first = deformer.start;
    last = deformer.end;
  } else {
    first = start;
    last = end;
  }
}

std::shared_ptr<const Mesh> MeshAnimation::at(const std::shared_ptr<const Mesh>& base, float t) const {
  if (kind == Kind::kDeformer) return std::make_shared<const Mesh>(deformer.apply(*base, t));
  if (kind != Kind::kFrames || frames.empty()) return base;
  const float p = end > start ? std::clamp((t - start) / (end - start), 0.0f, 1.0f) : 0.0f;
  const auto k = static_cast<size_t>(std::lround(p * float(frames.size() - 1)));
  return frames[std::min(k, frames.size() - 1)];
}

}  // namespace ab
