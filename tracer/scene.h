// Scenes: base meshes (loaded once), instances of them under transforms, materials, lights and a
// camera, read from the XML format described in docs/scenes.md.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "accel/core/mesh.h"
#include "tracer/animation.h"
#include "tracer/camera.h"
#include "tracer/deform.h"
#include "tracer/light.h"
#include "tracer/material.h"
#include "tracer/transform.h"

namespace ab {

/// A base mesh, declared once and shared by every instance that names it.
struct SceneMesh {
  std::string name;
  std::string source;                ///< "file PATH", "generator NAME ..." or "inline" (for reports)
  std::shared_ptr<const Mesh> mesh;  ///< the mesh at the scene's time (the base mesh when static)
  std::shared_ptr<const Mesh> base;  ///< the base mesh the animation starts from (frames: the first)
  MeshAnimation animation;           ///< how it deforms over time (static by default)
};

/// One placement of a base mesh. Its index in Scene::instances is its `inst` id (document order).
struct SceneInstance {
  uint32_t mesh = 0;            ///< index into Scene::meshes
  uint32_t material = 0;        ///< index into Scene::materials
  Transform transform;          ///< the transform at the scene's time
  AnimatedTransform animation;  ///< its elements and keyframes (evaluated into `transform`)
};

/// Defaults for `accelbench render` (command-line options override them).
struct RenderSettings {
  int width = 256;
  int height = 256;
  int spp = 16;           ///< samples per pixel
  int max_depth = 6;      ///< recursion limit (specular, glossy and diffuse bounces)
  int diffuse_depth = 1;  ///< how many of those bounces may be diffuse (indirect light)
  int frames = 30;        ///< frames of the whole animation for `render --frames A-B`
  vec3 background{0.0f};  ///< radiance of rays that leave the scene
  vec3 ambient{0.0f};     ///< constant light added on diffuse surfaces
};

/// A whole scene.
struct Scene {
  std::string path;  ///< the file it came from (for messages)
  std::vector<SceneMesh> meshes;
  std::vector<SceneInstance> instances;
  std::vector<Material> materials;  ///< materials[0] is the default ("default", grey diffuse)
  std::vector<PointLight> point_lights;
  std::vector<AreaLight> area_lights;
  Camera camera;
  RenderSettings render;
  float time_first = 0.0f;  ///< scene time of the first key of the animation (0 when static)
  float time_last = 0.0f;   ///< scene time of the last key (== time_first when static)
  float time = 0.0f;        ///< the normalized time in [0, 1] the meshes and transforms are evaluated at

  /// True when some instance's transform or some mesh changes over time.
  bool animated() const { return time_last > time_first; }

  /// World-space triangles over all instances.
  uint64_t triangle_count() const;
  AABB bounds;  ///< world bounds, filled by the parser (empty: world_bounds() computes them)

  /// World bounds of all instances (their transformed mesh vertices).
  AABB world_bounds() const;
  /// Computes the world bounds from the instances (every transformed vertex).
  AABB compute_world_bounds() const;
  /// World-space geometric normal (unnormalized, by the inverse transpose) of a hit.
  vec3 hit_normal(const Hit& hit) const;
};

/// Reads a scene file (XML, or glTF 2.0 for .gltf and .glb: tracer/gltf.h), evaluated at time 0. Mesh files
/// are resolved relative to the scene file's folder. Throws InputError naming the file and line for malformed
/// XML, unknown elements or references, bad numbers, missing or malformed meshes and singular transforms.
Scene load_scene(const std::string& path);
/// Parses scene text; `path` names it in messages and `base_dir` resolves mesh files.
Scene parse_scene(const std::string& text, const std::string& path, const std::string& base_dir);

/// The scene at normalized time u in [0, 1] (scene time time_first + u (time_last - time_first)):
/// every instance's transform and every deforming mesh evaluated there; a static scene comes back
/// unchanged. Throws InputError naming the scene file when a transform is singular at that time.
Scene scene_at(const Scene& scene, float u);

/// The normalized time of frame `frame` of `frames` (frame / (frames - 1); 0 for a single frame).
/// Throws InputError when frames is 0 or frame >= frames.
float frame_time(uint64_t frame, uint64_t frames);

/// The scene as one world-space mesh: instances in document order, each instance's triangles in
/// base-mesh order (vertices of every instance transformed by its object-to-world matrix).
Mesh flatten_scene(const Scene& scene);

}  // namespace ab
