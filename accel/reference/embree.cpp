#include "accel/reference/embree.h"

#include "accel/core/error.h"
#include "accel/core/registry.h"

#include <atomic>
#include <cstring>
#include <mutex>

namespace ab {

namespace {
std::atomic<int64_t> g_embree_bytes{0};

bool monitor(void*, ssize_t bytes, bool) {
  g_embree_bytes += bytes;
  return true;
}
}  // namespace

RTCDevice embree_device() {
  static RTCDevice device = [] {
    RTCDevice d = rtcNewDevice(nullptr);
    if (!d) throw InputError("embree: cannot create a device");
    rtcSetDeviceMemoryMonitorFunction(d, monitor, nullptr);
    return d;
  }();
  return device;
}

int64_t embree_bytes_in_use() { return g_embree_bytes.load(); }

EmbreeMesh::EmbreeMesh(std::shared_ptr<const TrianglePrims> prims, Params& params) : prims_(std::move(prims)) {
  const std::string q = params.get_choice("quality", "medium", {"low", "medium", "high"});
  quality_ = q == "low" ? RTC_BUILD_QUALITY_LOW : q == "high" ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;
  config_ = params.effective();
}

EmbreeMesh::~EmbreeMesh() {
  if (scene_) rtcReleaseScene(scene_);
}

void EmbreeMesh::do_build() {
  if (scene_) rtcReleaseScene(scene_);
  RTCDevice device = embree_device();
  const int64_t bytes_before = embree_bytes_in_use();
  scene_ = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene_, quality_);
  const Mesh& mesh = prims_->mesh();
  if (mesh.size() > 0) {
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, quality_);
    // Embree reads vertex buffers with 16-byte loads: allocate through it (it pads the last element).
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 sizeof(float) * 3, mesh.vertices.size()));
    std::memcpy(vertices, mesh.vertices.data(), sizeof(float) * 3 * mesh.vertices.size());
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   sizeof(uint32_t) * 3, mesh.size()));
    std::memcpy(indices, mesh.triangles.data(), sizeof(uint32_t) * 3 * mesh.size());
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene_, geom, 0);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(scene_);
  stats_ = BuildStats{};
  stats_.primitives = mesh.size();
  stats_.references = mesh.size();
  const int64_t grown = embree_bytes_in_use() - bytes_before;
  stats_.bytes = grown > 0 ? static_cast<uint64_t>(grown) : 0;
  stats_.extra["note"] = "bytes from Embree's memory monitor (BVH plus its copy of the mesh buffers)";
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
    RTCRayHit rh = to_embree(rays[i]);
    rtcOccluded1(scene_, &context, &rh.ray);
    out[i] = rh.ray.tfar < 0.0f;  // Embree sets tfar = -inf when occluded
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
const Registrar kRegisterEmbree{[] {
  AcceleratorInfo info;
  info.name = "embree";
  info.description = "Intel Embree 3 (the reference); quality=low|medium|high";
  info.order = 1;
  info.is_reference = true;
  info.make_for_mesh = [](std::shared_ptr<const TrianglePrims> p, Params& params) -> std::unique_ptr<Accelerator> {
    return std::make_unique<EmbreeMesh>(std::move(p), params);
  };
  return info;
}()};
}  // namespace

}  // namespace ab
