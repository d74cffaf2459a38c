#include "harness/target.h"

#include "accel/core/error.h"
#include "accel/core/motion.h"
#include "accel/core/registry.h"
#include "datasets/mesh_io.h"
#include "harness/selection.h"
#include "tracer/scene.h"
#include "tracer/scene_accel.h"
#include "tracer/scene_motion.h"
#include "tracer/workload.h"

namespace ab {

Target mesh_target(std::shared_ptr<const Mesh> mesh, std::string name) {
  Target t;
  t.path = std::move(name);
  t.triangles = mesh->size();
  t.bounds = mesh->bounds();
  t.mesh = std::move(mesh);
  return t;
}

Target scene_target(std::shared_ptr<const Scene> scene, std::string path) {
  Target t;
  t.path = std::move(path);
  t.triangles = scene->triangle_count();
  t.bounds = scene->world_bounds();
  t.scene = std::move(scene);
  return t;
}

Target load_target(const std::string& mesh_path, const std::string& scene_path, float time) {
  if (mesh_path.empty() == scene_path.empty()) throw InputError("give exactly one of --mesh and --scene");
  if (!scene_path.empty()) {
    Scene loaded = load_scene(scene_path);
    if (time != 0.0f && loaded.animated()) loaded = scene_at(loaded, time);
    return scene_target(std::make_shared<const Scene>(std::move(loaded)), scene_path);
  }
  return mesh_target(std::make_shared<const Mesh>(read_mesh(mesh_path)), mesh_path);
}

std::unique_ptr<Accelerator> make_target_accelerator(const Target& target, const std::string& name,
                                                     Params params, const std::string& top,
                                                     const std::string& bottom) {
  if (target.scene) return make_scene_accelerator(target.scene, name, std::move(params), top, bottom);
  if (!top.empty() || !bottom.empty())
    throw InputError("--accel-top and --accel-bottom apply to scenes only (" + target.path + " is a mesh)");
  return make_accelerator(name, std::make_shared<const TrianglePrims>(target.mesh), std::move(params));
}

namespace {
/// n scaled to unit length (+z when it has none: a degenerate triangle).
vec3 unit_or_z(const vec3& n) {
  const float len = glm::length(n);
  return len > 0.0f ? n / len : vec3(0.0f, 0.0f, 1.0f);
}
}  // namespace

RayTarget ray_target(const Target& target) {
  // The structure that finds surface points: default_structure(), deterministic and identical to brute.
  std::unique_ptr<Accelerator> built = make_target_accelerator(target, default_structure(), Params{});
  built->build();
  std::shared_ptr<const Accelerator> accel = std::move(built);
  RayTarget rt;
  rt.bounds = target.bounds;
  rt.trace = [accel](std::span<const Ray> rays, std::span<Hit> hits) { accel->intersect(rays, hits); };
  if (target.scene) {
    const std::shared_ptr<const Scene> scene = target.scene;
    rt.normal = [scene](const Hit& h) { return unit_or_z(scene->hit_normal(h)); };
    return rt;
  }
  const std::shared_ptr<const Mesh> mesh = target.mesh;
  rt.normal = [mesh](const Hit& h) {
    const Triangle t = mesh->triangle(h.prim);
    return unit_or_z(glm::cross(t.v1 - t.v0, t.v2 - t.v0));
  };
  return rt;
}

std::vector<Ray> make_target_rays(const Target& target, const std::string& kind, uint64_t count,
                                  uint64_t seed, uint32_t views) {
  return make_target_rays(target, ray_target(target), kind, count, seed, views);
}

std::vector<Ray> make_target_rays(const Target& target, const RayTarget& rt, const std::string& kind,
                                  uint64_t count, uint64_t seed, uint32_t views) {
  if (target.scene && is_scene_ray_kind(kind) && views == 1)
    return make_scene_rays(*target.scene, rt.trace, kind, count, seed);
  return make_rays(kind, rt, count, seed, views);
}

HitTriangleAtFn hit_triangles(const Target& target) {
  if (target.scene) {
    const std::shared_ptr<const Scene> scene = target.scene;
    auto motion = std::make_shared<const SceneMotion>(scene_motion(*scene));  // nothing when still
    return [scene, motion](const Hit& h, float time) {
      const SceneInstance& inst = scene->instances.at(h.inst);
      Triangle t = scene->meshes[inst.mesh].mesh->triangle(h.prim);
      const auto& steps = motion->meshes[inst.mesh];
      if (!steps.empty()) {  // the one triangle interpolation (MotionTrianglePrims::triangle_at)
        const MotionSegment seg = motion_segment(time, static_cast<uint32_t>(steps.size()));
        t = lerp_triangle(steps[seg.index]->triangle(h.prim), steps[seg.index + 1]->triangle(h.prim),
                          seg.fraction);
      }
      if (h.inst < motion->instances.size() && !motion->instances[h.inst].empty()) {
        const glm::mat4 m = matrix_at(motion->instances[h.inst], time);  // as instance_to_world_at
        const auto point = [&](const vec3& p) { return vec3(m * glm::vec4(p, 1.0f)); };
        return Triangle{point(t.v0), point(t.v1), point(t.v2)};
      }
      return Triangle{inst.transform.point(t.v0), inst.transform.point(t.v1), inst.transform.point(t.v2)};
    };
  }
  const std::shared_ptr<const Mesh> mesh = target.mesh;
  return [mesh](const Hit& h, float) { return mesh->triangle(h.prim); };
}

}  // namespace ab
