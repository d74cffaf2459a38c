// Motion blur in scenes: a ray's time u in [0, 1] is a position within the camera's shutter around the
// selected frame, scene time t(u) = t_frame + open + u (close - open) (keys' units; CONTRACT "Scene time").
// The motion over the shutter is sampled at the camera's motion_steps evenly spaced time steps and
// interpolated linearly between them (accel/core/motion.h), by structures of the project and Embree alike.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "accel/core/mesh.h"
#include "tracer/scene.h"

namespace ab {

/// What moves during the shutter, as time steps.
struct SceneMotion {
  std::vector<float> step_times;  ///< scene time of each time step
  /// Per base mesh: the mesh at each step (empty: it does not change during the shutter).
  std::vector<std::vector<std::shared_ptr<const Mesh>>> meshes;
  /// Per instance: its object-to-world matrix at each step (empty: it does not move).
  std::vector<std::vector<glm::mat4>> instances;

  /// True when something moves.
  bool any() const;
};

/// The scene time (keys' units) of ray time u in [0, 1] for the scene at its selected time.
float shutter_scene_time(const Scene& scene, float u);

/// The scene's motion over the camera's shutter; nothing moves when the shutter is closed or the scene is
/// static. Throws InputError naming the scene file when a transform is singular at a time step.
SceneMotion scene_motion(const Scene& scene);

/// World bounds of the scene over the whole shutter (every instance at every time step).
AABB motion_world_bounds(const Scene& scene, const SceneMotion& motion);

/// The scene as one moving world-space mesh (flatten_scene at each time step: instances in document order,
/// each instance's triangles in base-mesh order); its vertices are interpolated between the steps in world
/// space, so its hits are those of a flattened motion, not of the two-level one.
std::vector<std::shared_ptr<const Mesh>> flatten_scene_motion(const Scene& scene, const SceneMotion& motion);

}  // namespace ab
