// Random numbers and sample warps for the tracer. Every pixel seeds its own generator from
// (image seed, pixel index), so an image does not depend on how pixels are spread over threads.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "accel/core/aabb.h"

namespace ab {

/// O'Neill 2014, "PCG: a family of simple fast space-efficient statistically good algorithms for
/// random number generation" (PCG-XSH-RR, 64-bit state, 32-bit output).
class Rng {
 public:
  /// A generator for stream (seed, sequence).
  Rng(uint64_t seed, uint64_t sequence) {
    inc_ = (sequence << 1u) | 1u;
    next();
    state_ += seed;
    next();
  }
  /// Next 32 random bits.
  uint32_t next() {
    const uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31));
  }
  /// Uniform float in [0, 1).
  float uniform() { return float(next() >> 8) * 0x1p-24f; }
  /// Uniform integer in [0, n).
  uint32_t below(uint32_t n) { return static_cast<uint32_t>((uint64_t(next()) * n) >> 32); }

 private:
  uint64_t state_ = 0;
  uint64_t inc_ = 1;
};

/// Stratified, jittered 2D samples for one pixel (Cook 1984: each dimension pair is stratified and
/// the strata of different pairs are matched by random permutations). n samples form a jittered
/// k x k grid when n = k^2, a Latin hypercube otherwise.
class Stratified2D {
 public:
  /// Prepares n samples with a fresh permutation drawn from rng.
  Stratified2D(uint32_t n, Rng& rng);
  /// Sample i in [0,1)^2 (jitter drawn from rng).
  glm::vec2 get(uint32_t i, Rng& rng) const;

 private:
  uint32_t n_, k_;
  std::vector<uint32_t> perm_, perm_y_;
};

/// Uniform point on the unit disk (concentric map: Shirley and Chiu 1997).
glm::vec2 sample_disk(float u, float v);
/// Cosine-weighted direction about unit normal n.
vec3 sample_cosine_hemisphere(const vec3& n, float u, float v);
/// Direction in a Phong lobe cos^e about unit axis a.
vec3 sample_phong_lobe(const vec3& a, float exponent, float u, float v);
/// An orthonormal basis (t, b) completing unit vector n (Duff et al. 2017, "Building an Orthonormal
/// Basis, Revisited").
void orthonormal_basis(const vec3& n, vec3& t, vec3& b);

}  // namespace ab
