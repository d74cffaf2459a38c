// Embree's own two-level instancing over a scene (rtcNewGeometry(RTC_GEOMETRY_TYPE_INSTANCE)), the
// reference that `verify --scene` checks the project's two-level structures against.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "accel/core/accelerator.h"
#include "accel/core/mesh.h"
#include "accel/core/params.h"
#include "accel/reference/embree_device.h"

namespace ab {

/// One instance: a base mesh index and its object-to-world matrix.
struct EmbreeInstanceInput {
  uint32_t mesh = 0;         ///< index of the base mesh
  glm::mat4 to_world{1.0f};  ///< object-to-world matrix
};

/// Creates (does not build) an Embree scene: one Embree scene per base mesh, each committed once, and
/// a top scene with one instance geometry per instance (geometry id = instance index, so Embree's
/// instID is the contract's `inst`). Parameters: EmbreeConfig (quality=low|medium|high, default medium),
/// checked and recorded as the registry does for every structure (name `embree`, effective config).
std::unique_ptr<Accelerator> make_embree_scene(std::vector<std::shared_ptr<const Mesh>> meshes,
                                               std::vector<EmbreeInstanceInput> instances, Params& params);

}  // namespace ab
