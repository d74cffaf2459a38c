#include "accel/reference/embree_scene.h"

#include <chrono>
#include <glm/gtc/type_ptr.hpp>
#include <string>

#include "accel/core/error.h"
#include "accel/core/instances.h"

namespace ab {

namespace {

/// Embree over a scene with its own instances. Every Embree scene of it is robust (RTC_SCENE_FLAG_ROBUST:
/// no culling shortcuts, as befits the reference of `verify --scene`).
class EmbreeScene final : public Accelerator, public EmbreeSceneFrames {
 public:
  EmbreeScene(std::vector<std::shared_ptr<const Mesh>> meshes, std::vector<EmbreeInstanceInput> instances,
              const EmbreeConfig& config, std::vector<std::vector<std::shared_ptr<const Mesh>>> mesh_steps)
      : meshes_(std::move(meshes)),
        mesh_steps_(std::move(mesh_steps)),
        instances_(std::move(instances)),
        config_(config) {
    mesh_steps_.resize(meshes_.size());
    for (const auto& inst : instances_) {
      if (inst.mesh >= meshes_.size()) throw InputError("embree: instance of a missing mesh");
      std::vector<const Mesh*> shapes{meshes_[inst.mesh].get()};
      for (const auto& m : mesh_steps_[inst.mesh]) shapes.push_back(m.get());
      for (const Mesh* m : shapes) {
        bounds_.extend(transform_bounds(m->bounds(), inst.to_world));
        for (const glm::mat4& s : inst.to_world_steps) bounds_.extend(transform_bounds(m->bounds(), s));
      }
    }
  }
  ~EmbreeScene() override { release(); }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  AABB bounds() const override { return bounds_; }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const override {
    for (size_t i = 0; i < rays.size(); ++i) {
      hits[i] = Hit{};
      intersect_one(rays[i], hits[i], kInvalidId, nullptr);
    }
  }
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out) const override {
    for (size_t i = 0; i < rays.size(); ++i) out[i] = occluded_one(rays[i], nullptr);
  }
  void intersect_counted(std::span<const Ray> rays, std::span<Hit> hits, RayCounters&) const override {
    intersect(rays, hits);
  }
  void occluded_counted(std::span<const Ray> rays, std::span<uint8_t> out, RayCounters&) const override {
    occluded(rays, out);
  }
  void intersect_one(const Ray& ray, Hit& best, uint32_t, RayCounters*) const override;
  bool occluded_one(const Ray& ray, RayCounters*) const override;

  void build_for_refit() override { for_refit_ = true; }
  bool refit_frame(const std::vector<std::shared_ptr<const Mesh>>& meshes,
                   const std::vector<EmbreeInstanceInput>& instances) override;

 protected:
  void do_build() override;
  void gather_stats(BuildStats& stats) const override;

 private:
  void commit_top();
  void release();
  /// The scene flags of every level: robust, and dynamic when built for refitting.
  RTCSceneFlags flags() const {
    return for_refit_ ? RTCSceneFlags(RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC) : RTC_SCENE_FLAG_ROBUST;
  }
  /// The build quality of every scene: low when built for refitting (see EmbreeSceneFrames).
  RTCBuildQuality scene_quality() const { return for_refit_ ? RTC_BUILD_QUALITY_LOW : config_.quality; }

  std::vector<std::shared_ptr<const Mesh>> meshes_;
  std::vector<std::vector<std::shared_ptr<const Mesh>>> mesh_steps_;  ///< per mesh: its time steps, or none
  std::vector<EmbreeInstanceInput> instances_;
  EmbreeConfig config_;
  AABB bounds_;
  std::vector<RTCScene> bottoms_;
  RTCScene top_ = nullptr;
  bool for_refit_ = false;
};

void EmbreeScene::do_build() {
  release();
  const int64_t bytes_before = embree_bytes_in_use();
  const RTCBuildQuality geometry_quality = for_refit_ ? RTC_BUILD_QUALITY_REFIT : config_.quality;
  for (size_t m = 0; m < meshes_.size(); ++m)
    bottoms_.push_back(
        mesh_steps_[m].empty()
            ? commit_mesh_scene(*meshes_[m], scene_quality(), flags(), geometry_quality)
            : commit_motion_mesh_scene(mesh_steps_[m], config_.quality, RTC_SCENE_FLAG_ROBUST));
  commit_top();
  const int64_t grown = embree_bytes_in_use() - bytes_before;
  stats_.bytes = grown > 0 ? static_cast<uint64_t>(grown) : 0;
}

/// The top scene: one instance geometry per instance, its id the instance's index.
void EmbreeScene::commit_top() {
  RTCDevice device = embree_device();
  top_ = rtcNewScene(device);
  rtcSetSceneFlags(top_, flags());
  rtcSetSceneBuildQuality(top_, scene_quality());
  for (size_t i = 0; i < instances_.size(); ++i) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, bottoms_[instances_[i].mesh]);
    const std::vector<glm::mat4>& steps = instances_[i].to_world_steps;
    rtcSetGeometryTimeStepCount(g, steps.empty() ? 1u : static_cast<unsigned>(steps.size()));
    if (steps.empty())
      rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, glm::value_ptr(instances_[i].to_world));
    for (size_t k = 0; k < steps.size(); ++k)
      rtcSetGeometryTransform(g, unsigned(k), RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, glm::value_ptr(steps[k]));
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(top_, g, static_cast<unsigned>(i));
    rtcReleaseGeometry(g);
  }
  rtcCommitScene(top_);
  check_embree_error("scene build");
}

bool EmbreeScene::refit_frame(const std::vector<std::shared_ptr<const Mesh>>& meshes,
                              const std::vector<EmbreeInstanceInput>& instances) {
  if (!for_refit_ || !top_ || meshes.size() != meshes_.size() || instances.size() != instances_.size())
    return false;
  for (size_t m = 0; m < meshes.size(); ++m)
    if (meshes[m]->vertices.size() != meshes_[m]->vertices.size() || meshes[m]->size() != meshes_[m]->size())
      return false;
  for (size_t i = 0; i < instances.size(); ++i)
    if (instances[i].mesh != instances_[i].mesh || !instances[i].to_world_steps.empty()) return false;
  for (const auto& steps : mesh_steps_)
    if (!steps.empty()) return false;  // motion blur: rebuilt every frame
  const auto start = std::chrono::steady_clock::now();
  for (size_t m = 0; m < meshes.size(); ++m) {
    if (meshes[m] != meshes_[m]) update_mesh_vertices(bottoms_[m], *meshes[m]);
    meshes_[m] = meshes[m];
  }
  instances_ = instances;
  bounds_ = AABB{};
  for (size_t i = 0; i < instances_.size(); ++i) {
    RTCGeometry g = rtcGetGeometry(top_, static_cast<unsigned>(i));
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, glm::value_ptr(instances_[i].to_world));
    rtcCommitGeometry(g);
    bounds_.extend(transform_bounds(meshes_[instances_[i].mesh]->bounds(), instances_[i].to_world));
  }
  rtcCommitScene(top_);
  check_embree_error("scene refit");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const uint64_t bytes = stats_.bytes;
  stats_ = BuildStats{};
  stats_.build_seconds = seconds;
  stats_.bytes = bytes;
  gather_stats(stats_);
  return true;
}

void EmbreeScene::gather_stats(BuildStats& stats) const {
  uint64_t tris = 0;
  for (const auto& m : meshes_) tris += m->size();
  stats.primitives = tris;
  stats.references = tris;
  stats.extra = {
      {"instances", instances_.size()},
      {"base_meshes", meshes_.size()},
      {"note", "bytes from Embree's memory monitor (both levels plus its copies of the mesh buffers)"}};
}

void EmbreeScene::release() {
  if (top_) rtcReleaseScene(top_);
  top_ = nullptr;
  for (RTCScene s : bottoms_) rtcReleaseScene(s);
  bottoms_.clear();
}

void EmbreeScene::intersect_one(const Ray& ray, Hit& best, uint32_t, RayCounters*) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh = to_embree(ray, std::min(ray.tmax, best.t));
  rtcIntersect1(top_, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
  if (!is_better_hit(rh.ray.tfar, rh.hit.instID[0], rh.hit.primID, best)) return;
  best = {rh.ray.tfar, rh.hit.primID, rh.hit.instID[0], rh.hit.u, rh.hit.v};
}

bool EmbreeScene::occluded_one(const Ray& ray, RayCounters*) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r = to_embree(ray).ray;
  rtcOccluded1(top_, &ctx, &r);
  return embree_occluded(r);
}

}  // namespace

std::unique_ptr<Accelerator> make_embree_scene(
    std::vector<std::shared_ptr<const Mesh>> meshes, std::vector<EmbreeInstanceInput> instances,
    Params& params, std::vector<std::vector<std::shared_ptr<const Mesh>>> mesh_steps) {
  const EmbreeConfig config = EmbreeConfig::read(params);
  params.finish(kEmbreeName);
  auto accel =
      std::make_unique<EmbreeScene>(std::move(meshes), std::move(instances), config, std::move(mesh_steps));
  accel->identify(kEmbreeName, params.effective());
  return accel;
}

}  // namespace ab
