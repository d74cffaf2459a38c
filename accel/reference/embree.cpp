#include "accel/reference/embree.h"

#include <algorithm>

#include "accel/core/registry.h"

namespace ab {

EmbreeMesh::EmbreeMesh(std::shared_ptr<const TrianglePrims> prims, const Config& config)
    : prims_(std::move(prims)), config_(config) {}

EmbreeMesh::~EmbreeMesh() {
  if (scene_) rtcReleaseScene(scene_);
}

void EmbreeMesh::do_build() {
  if (scene_) rtcReleaseScene(scene_);
  scene_ = nullptr;
  const int64_t bytes_before = embree_restart_peak();
  scene_ = commit_mesh_scene(prims_->mesh(), config_.quality, RTC_SCENE_FLAG_NONE);
  dynamic_ = false;
  const int64_t grown = embree_bytes_in_use() - bytes_before;
  stats_.bytes = grown > 0 ? static_cast<uint64_t>(grown) : 0;
  // The monitor's peak: Embree's own allocator, which the heap accounting does not see (build() adds it).
  stats_.peak_bytes = uint64_t(std::max<int64_t>(0, embree_peak_bytes() - bytes_before));
}

void EmbreeMesh::commit_frame(std::shared_ptr<const TrianglePrims> prims, RTCBuildQuality quality) {
  const size_t old_vertices = prims_->mesh().vertices.size();
  prims_ = std::move(prims);
  const Mesh& mesh = prims_->mesh();
  if (!dynamic_ || quality != geometry_quality_ || mesh.vertices.size() != old_vertices || mesh.size() == 0) {
    if (scene_) rtcReleaseScene(scene_);
    // Embree honours a geometry's own quality (RTC_BUILD_QUALITY_REFIT) only under a low-quality scene,
    // whose two-level build builds each geometry apart (rtcSetGeometryBuildQuality(3)).
    const RTCBuildQuality scene_quality =
        quality == RTC_BUILD_QUALITY_REFIT ? RTC_BUILD_QUALITY_LOW : quality;
    scene_ = commit_mesh_scene(mesh, scene_quality, RTC_SCENE_FLAG_DYNAMIC, quality);
    dynamic_ = true;
    geometry_quality_ = quality;
    return;
  }
  update_mesh_vertices(scene_, mesh);
  check_embree_error("dynamic commit");
}

bool EmbreeMesh::do_refit_triangles(std::shared_ptr<const TrianglePrims> prims) {
  if (!prims || prims->size() != prims_->size()) return false;
  commit_frame(std::move(prims), RTC_BUILD_QUALITY_REFIT);
  return true;
}

void EmbreeMesh::gather_stats(BuildStats& stats) const {
  stats.primitives = prims_->size();
  stats.references = prims_->size();
  stats.extra["note"] = "bytes from Embree's memory monitor (BVH plus its copy of the mesh buffers)";
}

void EmbreeMesh::intersect(std::span<const Ray> rays, std::span<Hit> hits) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (size_t i = 0; i < rays.size(); ++i) {
    RTCRayHit rh = to_embree(rays[i]);
    rtcIntersect1(scene_, &context, &rh);
    Hit& h = hits[i];
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      h = Hit{};
    } else {
      h = {rh.ray.tfar, rh.hit.primID, kInvalidId, rh.hit.u, rh.hit.v};
    }
  }
}

void EmbreeMesh::occluded(std::span<const Ray> rays, std::span<uint8_t> out) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  for (size_t i = 0; i < rays.size(); ++i) {
    RTCRay r = to_embree(rays[i]).ray;
    rtcOccluded1(scene_, &context, &r);
    out[i] = embree_occluded(r);
  }
}

void EmbreeMesh::intersect_counted(std::span<const Ray> rays, std::span<Hit> hits, RayCounters&) const {
  intersect(rays, hits);
}

void EmbreeMesh::occluded_counted(std::span<const Ray> rays, std::span<uint8_t> out, RayCounters&) const {
  occluded(rays, out);
}

void EmbreeMesh::intersect_one(const Ray& ray, Hit& best, uint32_t inst, RayCounters*) const {
  Ray r = ray;
  r.tmax = std::min(r.tmax, best.t);
  Hit h;
  intersect(std::span<const Ray>(&r, 1), std::span<Hit>(&h, 1));
  if (h.found() && is_better_hit(h.t, inst, h.prim, best)) best = {h.t, h.prim, inst, h.u, h.v};
}

bool EmbreeMesh::occluded_one(const Ray& ray, RayCounters*) const {
  uint8_t o = 0;
  occluded(std::span<const Ray>(&ray, 1), std::span<uint8_t>(&o, 1));
  return o != 0;
}

namespace {
/// Through the registry like every structure (create_structure reads the Config once; the registry records
/// the name and the effective parameters), over meshes only: a scene uses Embree's own instancing
/// (embree_scene.h).
const Registrar kRegisterEmbree{[] {
  AcceleratorInfo info;
  info.name = kEmbreeName;
  info.description = "Intel Embree 3 (the reference); quality=low|medium|high";
  info.order = 1;
  info.is_reference = true;
  info.make_for_mesh = create_structure<EmbreeMesh>;
  return info;
}()};
}  // namespace

}  // namespace ab
