// Embree's own two-level instancing over a scene (rtcNewGeometry(RTC_GEOMETRY_TYPE_INSTANCE)), the
// reference that `verify --scene` checks the project's two-level structures against.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "accel/core/accelerator.h"
#include "accel/core/mesh.h"
#include "accel/core/params.h"

namespace ab {

/// The registry name of Embree.
inline constexpr const char* kEmbreeName = "embree";

/// One instance: a base mesh index and its object-to-world matrix.
struct EmbreeInstanceInput {
  uint32_t mesh = 0;
  glm::mat4 to_world{1.0f};
};

/// Creates (does not build) an Embree scene: one Embree scene per base mesh, each committed once, and
/// a top scene with one instance geometry per instance (geometry id = instance index, so Embree's
/// instID is the contract's `inst`). Parameter: quality=low|medium|high (build quality, default high).
std::unique_ptr<Accelerator> make_embree_scene(std::vector<std::shared_ptr<const Mesh>> meshes,
                                               std::vector<EmbreeInstanceInput> instances, Params& params);

}  // namespace ab
