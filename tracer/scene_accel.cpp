#include "tracer/scene_accel.h"

#include <algorithm>

#include "accel/core/error.h"
#include "accel/core/registry.h"

namespace ab {

Params level_params(const Params& params, const std::string& prefix, const std::string& other) {
  Params out;
  for (const auto& [k, v] : params.values()) {
    if (k.rfind(prefix + ".", 0) == 0)
      out.set(k.substr(prefix.size() + 1), v);
    else if (k.rfind(other + ".", 0) != 0)
      out.set(k, v);
  }
  return out;
}

SceneAccelerator::SceneAccelerator(std::shared_ptr<const Scene> scene, std::string top, std::string bottom,
                                   const Params& params)
    : scene_(std::move(scene)),
      motion_(scene_motion(*scene_)),
      top_name_(std::move(top)),
      bottom_name_(std::move(bottom)),
      top_params_(level_params(params, "top", "bottom")),
      bottom_params_(level_params(params, "bottom", "top")) {
  for (size_t m = 0; m < scene_->meshes.size(); ++m) {
    if (!motion_.meshes[m].empty())
      bottoms_.push_back(make_motion_accelerator(
          bottom_name_, std::make_shared<MotionTrianglePrims>(motion_.meshes[m]), bottom_params_));
    else
      bottoms_.push_back(make_accelerator(
          bottom_name_, std::make_shared<TrianglePrims>(scene_->meshes[m].mesh), bottom_params_));
  }
  // Checks the top-level name and parameters now (the real top is made once the bottoms are built).
  make_instance_accelerator(top_name_, std::make_shared<InstancePrims>(std::vector<Instance>{}), top_params_);
  bounds_ = motion_.any() ? motion_world_bounds(*scene_, motion_) : scene_->world_bounds();
}

std::string SceneAccelerator::name() const {
  return top_name_ == bottom_name_ ? top_name_ : top_name_ + "/" + bottom_name_;
}

nlohmann::json SceneAccelerator::config() const {
  nlohmann::json j = {{"top", top_name_}, {"bottom", bottom_name_}};
  if (top_) j["top_config"] = top_->config();
  if (!bottoms_.empty()) j["bottom_config"] = bottoms_.front()->config();
  return j;
}

void SceneAccelerator::do_build() {
  for (auto& b : bottoms_) b->build();
  instances_ = std::make_shared<InstancePrims>(make_instances());
  top_ = make_instance_accelerator(top_name_, instances_, top_params_);
  top_->build();
  aggregate_stats();
}

std::vector<Instance> SceneAccelerator::make_instances() const {
  std::vector<Instance> instances;
  instances.reserve(scene_->instances.size());
  for (size_t i = 0; i < scene_->instances.size(); ++i) {
    const SceneInstance& si = scene_->instances[i];
    instances.push_back({bottoms_[si.mesh], si.transform.to_world, si.transform.to_object, si.mesh,
                         i < motion_.instances.size() ? motion_.instances[i] : std::vector<glm::mat4>{}});
  }
  return instances;
}

// Both levels in one set of figures: nodes, leaves and bytes are sums (each bottom counted once,
// however many instances share it); depths add the deepest bottom below the top's leaves.
void SceneAccelerator::aggregate_stats() {
  const BuildStats& t = top_->stats();
  BuildStats s;
  s.primitives = 0;
  s.nodes = t.nodes;
  s.leaves = t.leaves;
  s.empty_leaves = t.empty_leaves;
  s.references = t.references;
  s.bytes = t.bytes + instances_->size() * sizeof(Instance);
  s.leaf_size_histogram = t.leaf_size_histogram;
  uint32_t deepest_bottom = 0;
  double depth_sum = t.mean_leaf_depth * double(t.leaves);
  nlohmann::json bottoms = nlohmann::json::array();
  for (size_t m = 0; m < bottoms_.size(); ++m) {
    const BuildStats& b = bottoms_[m]->stats();
    s.primitives += b.primitives;
    s.nodes += b.nodes;
    s.leaves += b.leaves;
    s.empty_leaves += b.empty_leaves;
    s.references += b.references;
    s.bytes += b.bytes;
    for (const auto& [size, count] : b.leaf_size_histogram) s.leaf_size_histogram[size] += count;
    deepest_bottom = std::max(deepest_bottom, b.max_depth);
    depth_sum += b.mean_leaf_depth * double(b.leaves);
    nlohmann::json bj = to_json(b);
    bj["mesh"] = scene_->meshes[m].name;
    bottoms.push_back(bj);
  }
  s.max_depth = t.max_depth + deepest_bottom;
  s.mean_leaf_depth = s.leaves ? depth_sum / double(s.leaves) : 0.0;
  s.extra = {{"instances", scene_->instances.size()},
             {"base_meshes", scene_->meshes.size()},
             {"world_triangles", scene_->triangle_count()},
             {"top", to_json(t)},
             {"bottoms", bottoms}};
  const double seconds = stats_.build_seconds;
  stats_ = s;
  stats_.build_seconds = seconds;
}

void embree_scene_inputs(const Scene& scene, std::vector<std::shared_ptr<const Mesh>>& meshes,
                         std::vector<EmbreeInstanceInput>& instances) {
  meshes.clear();
  instances.clear();
  for (const SceneMesh& m : scene.meshes) meshes.push_back(m.mesh);
  for (const SceneInstance& si : scene.instances) instances.push_back({si.mesh, si.transform.to_world, {}});
}

std::unique_ptr<Accelerator> make_scene_accelerator(std::shared_ptr<const Scene> scene,
                                                    const std::string& name, const Params& params,
                                                    const std::string& top, const std::string& bottom) {
  const std::string t = top.empty() ? name : top;
  const std::string b = bottom.empty() ? name : bottom;
  if (t == kEmbreeName && b == kEmbreeName) {
    SceneMotion motion = scene_motion(*scene);  // Embree's motion blur: the same time steps
    std::vector<std::shared_ptr<const Mesh>> meshes;
    std::vector<EmbreeInstanceInput> instances;
    embree_scene_inputs(*scene, meshes, instances);
    for (size_t i = 0; i < instances.size(); ++i)
      instances[i].to_world_steps = std::move(motion.instances[i]);
    Params p = params;
    return make_embree_scene(std::move(meshes), std::move(instances), p, std::move(motion.meshes));
  }
  return std::make_unique<SceneAccelerator>(std::move(scene), t, b, params);
}

}  // namespace ab
