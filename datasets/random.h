// A small deterministic random number generator for datasets: the same seed gives the same numbers
// with every compiler and standard library (no std:: distributions, whose output is unspecified).
#pragma once

#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>

namespace ab {

/// SplitMix64 finalizer (Steele, Lea and Flood 2014, "Fast splittable pseudorandom number
/// generators"): a bijective 64-bit mix, used for hashing seeds and indices.
inline uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Hash of a seed and a stream/index pair, for independent per-item generators.
inline uint64_t hash_seed(uint64_t seed, uint64_t a, uint64_t b = 0) {
  return mix64(mix64(mix64(seed) ^ (a + 0x9E3779B97F4A7C15ull)) ^ (b + 0x632BE59BD9B4E019ull));
}

/// SplitMix64 generator with explicit arithmetic: a 64-bit counter stepped by the golden gamma.
class Rng {
 public:
  /// A generator for (seed, stream); different streams are statistically independent.
  explicit Rng(uint64_t seed, uint64_t stream = 0) : state_(hash_seed(seed, stream)) {}

  /// Next 64 random bits.
  uint64_t next_u64() {
    state_ += 0x9E3779B97F4A7C15ull;
    return mix64(state_);
  }
  /// Uniform float in [0, 1) with 24 random bits (every value exactly representable).
  float uniform() { return static_cast<float>(next_u64() >> 40) * 0x1p-24f; }
  /// Uniform float in [lo, hi).
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [0, n) for n >= 1 (multiply-shift; the bias is below 2^-32 for n < 2^32).
  uint64_t below(uint64_t n) {
    return static_cast<uint64_t>((static_cast<unsigned __int128>(next_u64()) * n) >> 64);
  }
  /// Uniform point in the unit cube [0, 1)^3.
  glm::vec3 unit_cube() {
    const float x = uniform();
    const float y = uniform();
    return {x, y, uniform()};
  }
  /// Uniform direction on the unit sphere (Archimedes: z uniform in [-1, 1], azimuth uniform).
  glm::vec3 unit_sphere() {
    const float z = 1.0f - 2.0f * uniform();
    const float phi = 6.28318530717958647692f * uniform();
    const float r = std::sqrt(std::fmax(0.0f, 1.0f - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
  }

 private:
  uint64_t state_;
};

}  // namespace ab
