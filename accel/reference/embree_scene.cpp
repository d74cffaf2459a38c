#include "accel/reference/embree_scene.h"

#include <embree3/rtcore.h>

#include <glm/gtc/type_ptr.hpp>
#include <mutex>
#include <string>

#include "accel/core/error.h"
#include "accel/core/instances.h"

namespace ab {

namespace {

/// One Embree device for the process (created on first use).
RTCDevice scene_device() {
  static RTCDevice device = [] {
    RTCDevice d = rtcNewDevice("verbose=0");
    if (!d) throw InputError("embree: cannot create a device");
    return d;
  }();
  return device;
}

RTCBuildQuality quality_of(const std::string& q) {
  if (q == "low") return RTC_BUILD_QUALITY_LOW;
  if (q == "medium") return RTC_BUILD_QUALITY_MEDIUM;
  return RTC_BUILD_QUALITY_HIGH;
}

/// Embree over a scene with its own instances.
class EmbreeScene final : public Accelerator {
 public:
  EmbreeScene(std::vector<std::shared_ptr<const Mesh>> meshes, std::vector<EmbreeInstanceInput> instances,
              Params& params)
      : meshes_(std::move(meshes)), instances_(std::move(instances)) {
    quality_ = params.get_choice("quality", "high", {"low", "medium", "high"});
    config_ = params.effective();
    for (const auto& inst : instances_) {
      if (inst.mesh >= meshes_.size()) throw InputError("embree: instance of a missing mesh");
      bounds_.extend(transform_bounds(meshes_[inst.mesh]->bounds(), inst.to_world));
    }
  }
  ~EmbreeScene() override { release(); }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  std::string name() const override { return kEmbreeName; }
  nlohmann::json config() const override { return config_; }
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

 protected:
  void do_build() override;

 private:
  RTCScene build_mesh_scene(const Mesh& mesh) const;
  void release();

  std::vector<std::shared_ptr<const Mesh>> meshes_;
  std::vector<EmbreeInstanceInput> instances_;
  std::string quality_;
  nlohmann::json config_;
  AABB bounds_;
  std::vector<RTCScene> bottoms_;
  RTCScene top_ = nullptr;
};

RTCScene EmbreeScene::build_mesh_scene(const Mesh& mesh) const {
  RTCDevice device = scene_device();
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene, quality_of(quality_));
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geom, quality_of(quality_));
  // Embree reads vertex buffers with 16-byte loads: one float of padding at the end.
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), mesh.vertices.size() + 1));
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) v[3 * i + k] = mesh.vertices[i][k];
  auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                           3 * sizeof(uint32_t), mesh.triangles.size()));
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) t[3 * i + k] = mesh.triangles[i][k];
  rtcCommitGeometry(geom);
  rtcAttachGeometryByID(scene, geom, 0);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  return scene;
}

void EmbreeScene::do_build() {
  release();
  RTCDevice device = scene_device();
  for (const auto& m : meshes_) bottoms_.push_back(build_mesh_scene(*m));
  top_ = rtcNewScene(device);
  rtcSetSceneFlags(top_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(top_, quality_of(quality_));
  for (size_t i = 0; i < instances_.size(); ++i) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(g, bottoms_[instances_[i].mesh]);
    rtcSetGeometryTimeStepCount(g, 1);
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, glm::value_ptr(instances_[i].to_world));
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(top_, g, static_cast<unsigned>(i));
    rtcReleaseGeometry(g);
  }
  rtcCommitScene(top_);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw InputError("embree: scene build failed");
  stats_ = BuildStats{};
  uint64_t tris = 0;
  for (const auto& m : meshes_) tris += m->size();
  stats_.primitives = tris;
  stats_.references = tris;
  stats_.extra = {{"instances", instances_.size()}, {"base_meshes", meshes_.size()}};
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
  RTCRayHit rh{};
  rh.ray.org_x = ray.org.x;
  rh.ray.org_y = ray.org.y;
  rh.ray.org_z = ray.org.z;
  rh.ray.dir_x = ray.dir.x;
  rh.ray.dir_y = ray.dir.y;
  rh.ray.dir_z = ray.dir.z;
  rh.ray.tnear = ray.tmin;
  rh.ray.tfar = std::min(ray.tmax, best.t);
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(top_, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
  if (!is_better_hit(rh.ray.tfar, rh.hit.instID[0], rh.hit.primID, best)) return;
  best = {rh.ray.tfar, rh.hit.primID, rh.hit.instID[0], rh.hit.u, rh.hit.v};
}

bool EmbreeScene::occluded_one(const Ray& ray, RayCounters*) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r{};
  r.org_x = ray.org.x;
  r.org_y = ray.org.y;
  r.org_z = ray.org.z;
  r.dir_x = ray.dir.x;
  r.dir_y = ray.dir.y;
  r.dir_z = ray.dir.z;
  r.tnear = ray.tmin;
  r.tfar = ray.tmax;
  r.mask = 0xFFFFFFFFu;
  r.flags = 0;
  rtcOccluded1(top_, &ctx, &r);
  return r.tfar == -kInf;
}

}  // namespace

std::unique_ptr<Accelerator> make_embree_scene(std::vector<std::shared_ptr<const Mesh>> meshes,
                                               std::vector<EmbreeInstanceInput> instances, Params& params) {
  auto accel = std::make_unique<EmbreeScene>(std::move(meshes), std::move(instances), params);
  params.finish(kEmbreeName);
  return accel;
}

}  // namespace ab
