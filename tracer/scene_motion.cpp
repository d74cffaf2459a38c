#include "tracer/scene_motion.h"

#include <cstring>
#include <string>

#include "accel/core/error.h"
#include "accel/core/instances.h"

namespace ab {

namespace {

bool same_matrix(const glm::mat4& a, const glm::mat4& b) {
  return std::memcmp(&a, &b, sizeof(glm::mat4)) == 0;
}

/// The mesh's steps, or nothing when every step equals the mesh at the selected time.
std::vector<std::shared_ptr<const Mesh>> mesh_steps(const SceneMesh& m, const std::vector<float>& times) {
  if (!m.animation.animated()) return {};
  std::vector<std::shared_ptr<const Mesh>> steps;
  bool moves = false;
  for (float t : times) {
    steps.push_back(m.animation.at(m.base, t));
    moves = moves || steps.back()->vertices != m.mesh->vertices;
  }
  return moves ? steps : std::vector<std::shared_ptr<const Mesh>>{};
}

/// The instance's matrices at the steps, or nothing when every one equals its transform at the selected time.
std::vector<glm::mat4> instance_steps(const Scene& scene, size_t i, const std::vector<float>& times) {
  const SceneInstance& si = scene.instances[i];
  if (!si.animation.animated()) return {};
  std::vector<glm::mat4> steps;
  bool moves = false;
  for (float t : times) {
    Transform x;
    if (!si.animation.evaluate(t, x))
      throw InputError(scene.path + ": the transform of instance " + std::to_string(i) +
                       " is singular or not finite at scene time " + std::to_string(t) + " (shutter)");
    steps.push_back(x.to_world);
    moves = moves || !same_matrix(x.to_world, si.transform.to_world);
  }
  return moves ? steps : std::vector<glm::mat4>{};
}

}  // namespace

bool SceneMotion::any() const {
  for (const auto& m : meshes)
    if (!m.empty()) return true;
  for (const auto& i : instances)
    if (!i.empty()) return true;
  return false;
}

float shutter_scene_time(const Scene& scene, float u) {
  const float frame = scene.time_first + scene.time * (scene.time_last - scene.time_first);
  const Camera& c = scene.camera;
  return frame + c.shutter_open + u * (c.shutter_close - c.shutter_open);
}

SceneMotion scene_motion(const Scene& scene) {
  SceneMotion motion;
  motion.meshes.resize(scene.meshes.size());
  motion.instances.resize(scene.instances.size());
  if (!scene.camera.has_shutter() || !scene.animated()) return motion;
  const uint32_t steps = std::max<uint32_t>(2, scene.camera.motion_steps);
  for (uint32_t k = 0; k < steps; ++k)
    motion.step_times.push_back(shutter_scene_time(scene, float(double(k) / double(steps - 1))));
  for (size_t m = 0; m < scene.meshes.size(); ++m)
    motion.meshes[m] = mesh_steps(scene.meshes[m], motion.step_times);
  for (size_t i = 0; i < scene.instances.size(); ++i)
    motion.instances[i] = instance_steps(scene, i, motion.step_times);
  return motion;
}

AABB motion_world_bounds(const Scene& scene, const SceneMotion& motion) {
  AABB b = scene.world_bounds();
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    const SceneInstance& si = scene.instances[i];
    const auto& mesh_steps = motion.meshes[si.mesh];
    const auto& steps = motion.instances[i];
    for (size_t k = 0; k < motion.step_times.size(); ++k) {
      const Mesh& m = mesh_steps.empty() ? *scene.meshes[si.mesh].mesh : *mesh_steps[k];
      b.extend(transform_bounds(m.bounds(), steps.empty() ? si.transform.to_world : steps[k]));
    }
  }
  return b;
}

std::vector<std::shared_ptr<const Mesh>> flatten_scene_motion(const Scene& scene, const SceneMotion& motion) {
  std::vector<std::shared_ptr<const Mesh>> out;
  for (size_t k = 0; k < motion.step_times.size(); ++k) {
    auto flat = std::make_shared<Mesh>();
    for (size_t i = 0; i < scene.instances.size(); ++i) {
      const SceneInstance& si = scene.instances[i];
      const Mesh& m =
          motion.meshes[si.mesh].empty() ? *scene.meshes[si.mesh].mesh : *motion.meshes[si.mesh][k];
      const glm::mat4& to_world =
          motion.instances[i].empty() ? si.transform.to_world : motion.instances[i][k];
      const auto base = static_cast<uint32_t>(flat->vertices.size());
      for (const vec3& v : m.vertices) flat->vertices.push_back(vec3(to_world * glm::vec4(v, 1.0f)));
      for (const glm::uvec3& t : m.triangles) flat->triangles.push_back(t + glm::uvec3(base));
    }
    out.push_back(std::move(flat));
  }
  return out;
}

}  // namespace ab
