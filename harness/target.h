// What the CLI traces: a mesh file or a scene file, loaded once, with the structures built over it.
#pragma once

#include <memory>
#include <string>

#include "accel/core/accelerator.h"
#include "accel/core/mesh.h"
#include "accel/core/params.h"
#include "datasets/rays.h"
#include "harness/compare.h"

namespace ab {

struct Scene;  // tracer/scene.h

/// A loaded mesh (plain triangles, inst = 0xFFFFFFFF) or scene (instances).
struct Target {
  std::string path;                    ///< the file (or the name of an in-memory mesh)
  std::shared_ptr<const Mesh> mesh;    ///< set for a mesh
  std::shared_ptr<const Scene> scene;  ///< set for a scene
  uint64_t triangles = 0;              ///< triangles (for a scene: world-space triangles over all instances)
  AABB bounds;                         ///< world bounds
};

/// Loads --mesh F or --scene F (exactly one non-empty); a scene at normalized time `time` (a static
/// scene, and a mesh, ignore it). Throws InputError naming the file.
Target load_target(const std::string& mesh_path, const std::string& scene_path, float time = 0.0f);
/// Wraps an in-memory scene (a frame of an animation).
Target scene_target(std::shared_ptr<const Scene> scene, std::string path);
/// Wraps an in-memory mesh (generated meshes in suites and tests).
Target mesh_target(std::shared_ptr<const Mesh> mesh, std::string name);

/// Creates (not builds) accelerator `name` over the target. For a scene, `name` serves at both levels
/// unless `top` or `bottom` is given. Throws InputError / ParamError / UnknownAccelerator.
std::unique_ptr<Accelerator> make_target_accelerator(const Target& target, const std::string& name,
                                                     Params params, const std::string& top = "",
                                                     const std::string& bottom = "");

/// Exactly `count` rays of `kind` for the target: for a scene, the tracer's kinds (primary, dof, shadow,
/// glossy, diffuse: tracer/workload.h) use its camera and lights; every other kind (and every kind for
/// a mesh) comes from make_rays. `views` > 1 (primary only) places that many cameras around the bounds,
/// for a scene too (instead of its own camera). Throws InputError for an unknown kind or bad views.
std::vector<Ray> make_target_rays(const Target& target, const std::string& kind, uint64_t count,
                                  uint64_t seed, uint32_t views = 1);
/// The same with a RayTarget already made by ray_target(target) (so several ray sets share one build).
std::vector<Ray> make_target_rays(const Target& target, const RayTarget& rt, const std::string& kind,
                                  uint64_t count, uint64_t seed, uint32_t views = 1);

/// What ray generation needs of the target (bounds, a closest-hit trace through a fast structure of the
/// project, normals at hits).
RayTarget ray_target(const Target& target);

/// The world-space triangle of a hit on the target (used to explain disagreements with Embree).
HitTriangleAtFn hit_triangles(const Target& target);

}  // namespace ab
