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

/// One instance: a base mesh index and its object-to-world matrix (and, when it moves during the shutter,
/// that matrix at each time step: Embree interpolates FLOAT4X4 time steps linearly, as matrix_at does).
struct EmbreeInstanceInput {
  uint32_t mesh = 0;                      ///< index of the base mesh
  glm::mat4 to_world{1.0f};               ///< object-to-world matrix
  std::vector<glm::mat4> to_world_steps;  ///< at the shutter's time steps (empty: does not move)
};

/// What the `refit` strategy (tracer/update_strategy.h) asks of an Embree scene: built for refitting, as
/// EmbreeMesh::commit_frame does for a mesh (every level a low-quality RTC_SCENE_FLAG_DYNAMIC scene, the mesh
/// geometries at RTC_BUILD_QUALITY_REFIT: Embree honours a geometry's own quality only there), then moved to
/// each frame in place: changed vertex buffers refitted, instance transforms set, the top level committed.
class EmbreeSceneFrames {
 public:
  virtual ~EmbreeSceneFrames() = default;
  /// Makes the following build() commit every level for refitting.
  virtual void build_for_refit() = 0;
  /// Moves the built scene to a frame with the same meshes (vertex counts) and instances; a mesh given by
  /// the same pointer as before is kept. The wall time of the whole update is stats().build_seconds. False,
  /// with nothing changed, when the frame does not match or the scene was not built for refitting.
  virtual bool refit_frame(const std::vector<std::shared_ptr<const Mesh>>& meshes,
                           const std::vector<EmbreeInstanceInput>& instances) = 0;
};

/// Creates (does not build) an Embree scene: one Embree scene per base mesh, each committed once, and
/// a top scene with one instance geometry per instance (geometry id = instance index, so Embree's
/// instID is the contract's `inst`). Parameters: EmbreeConfig (quality=low|medium|high, default medium),
/// checked and recorded as the registry does for every structure (name `embree`, effective config). The
/// result is also an EmbreeSceneFrames.
/// `mesh_steps[m]`, when given and not empty, holds base mesh m at each time step (motion blur).
std::unique_ptr<Accelerator> make_embree_scene(
    std::vector<std::shared_ptr<const Mesh>> meshes, std::vector<EmbreeInstanceInput> instances,
    Params& params, std::vector<std::vector<std::shared_ptr<const Mesh>>> mesh_steps = {});

}  // namespace ab
