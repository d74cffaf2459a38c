// Deterministic mesh generators: same name, triangle count, seed and parameters give the same mesh
// (and the same bytes when written).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "accel/core/mesh.h"
#include "accel/core/params.h"

namespace ab {

/// One registered generator.
struct GeneratorInfo {
  std::string name;
  std::string description;
  /// Makes a mesh of about `triangles` triangles (within a few percent, never 0 for triangles >= 1
  /// unless impossible), reading its own parameters from params.
  std::function<Mesh(uint64_t triangles, uint64_t seed, Params& params)> make;
};

/// Every generator, in listing order.
const std::vector<GeneratorInfo>& generators();

/// Runs generator `name`; throws InputError for an unknown name, ParamError for bad/unknown params.
Mesh generate_mesh(const std::string& name, uint64_t triangles, uint64_t seed, Params params);

}  // namespace ab
