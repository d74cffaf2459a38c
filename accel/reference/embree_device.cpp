#include "accel/reference/embree_device.h"

#include <atomic>
#include <cstring>
#include <string>

#include "accel/core/error.h"

namespace ab {

namespace {
std::atomic<int64_t> g_embree_bytes{0};
std::atomic<int64_t> g_embree_peak{0};

bool monitor(void*, ssize_t bytes, bool) {
  const int64_t now = g_embree_bytes += bytes;
  int64_t peak = g_embree_peak.load();
  while (now > peak && !g_embree_peak.compare_exchange_weak(peak, now)) {
  }
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

int64_t embree_bytes_in_use() {
  return g_embree_bytes.load();
}

int64_t embree_restart_peak() {
  const int64_t now = g_embree_bytes.load();
  g_embree_peak.store(now);
  return now;
}

int64_t embree_peak_bytes() {
  return g_embree_peak.load();
}

EmbreeConfig EmbreeConfig::read(Params& params) {
  EmbreeConfig c;
  params.read("quality", c.quality,
              {{"low", RTC_BUILD_QUALITY_LOW},
               {"medium", RTC_BUILD_QUALITY_MEDIUM},
               {"high", RTC_BUILD_QUALITY_HIGH}});
  return c;
}

void check_embree_error(const char* what) {
  if (rtcGetDeviceError(embree_device()) != RTC_ERROR_NONE)
    throw InputError(std::string("embree: ") + what + " failed");
}

RTCScene commit_mesh_scene(const Mesh& mesh, RTCBuildQuality quality, RTCSceneFlags flags) {
  return commit_mesh_scene(mesh, quality, flags, quality);
}

namespace {

/// A committed scene of one triangle geometry with a vertex buffer per entry of `steps` (one: static).
RTCScene commit_steps_scene(const std::vector<const Mesh*>& steps, RTCBuildQuality quality,
                            RTCSceneFlags flags, RTCBuildQuality geometry_quality) {
  RTCDevice device = embree_device();
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneFlags(scene, flags);
  rtcSetSceneBuildQuality(scene, quality);
  const Mesh& mesh = *steps.front();
  if (mesh.size() > 0) {
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, geometry_quality);
    if (steps.size() > 1) rtcSetGeometryTimeStepCount(geom, static_cast<unsigned>(steps.size()));
    // Embree reads vertex buffers with 16-byte loads: allocated through it, the buffer is padded for that.
    for (size_t k = 0; k < steps.size(); ++k) {
      auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, unsigned(k),
                                                                   RTC_FORMAT_FLOAT3, sizeof(float) * 3,
                                                                   steps[k]->vertices.size()));
      std::memcpy(vertices, steps[k]->vertices.data(), sizeof(float) * 3 * steps[k]->vertices.size());
    }
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, sizeof(uint32_t) * 3, mesh.size()));
    std::memcpy(indices, mesh.triangles.data(), sizeof(uint32_t) * 3 * mesh.size());
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(scene, geom, 0);
    rtcReleaseGeometry(geom);
  }
  rtcCommitScene(scene);
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
    rtcReleaseScene(scene);
    throw InputError("embree: mesh build failed");
  }
  return scene;
}

}  // namespace

RTCScene commit_mesh_scene(const Mesh& mesh, RTCBuildQuality quality, RTCSceneFlags flags,
                           RTCBuildQuality geometry_quality) {
  return commit_steps_scene({&mesh}, quality, flags, geometry_quality);
}

RTCScene commit_motion_mesh_scene(const std::vector<std::shared_ptr<const Mesh>>& steps,
                                  RTCBuildQuality quality, RTCSceneFlags flags) {
  std::vector<const Mesh*> meshes;
  for (const auto& m : steps) meshes.push_back(m.get());
  return commit_steps_scene(meshes, quality, flags, quality);
}

void update_mesh_vertices(RTCScene scene, const Mesh& mesh) {
  if (mesh.size() > 0) {
    RTCGeometry geom = rtcGetGeometry(scene, 0);
    auto* vertices = static_cast<float*>(rtcGetGeometryBufferData(geom, RTC_BUFFER_TYPE_VERTEX, 0));
    std::memcpy(vertices, mesh.vertices.data(), sizeof(float) * 3 * mesh.vertices.size());
    rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(geom);
  }
  rtcCommitScene(scene);
}

}  // namespace ab
