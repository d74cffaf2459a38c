// What both Embree adapters (one mesh, a scene of instances) share, written once: the process's one Embree
// device with its memory monitor, the build quality with its one default, the upload of a triangle mesh as a
// committed Embree scene, and the conversion of a ray.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "accel/core/mesh.h"
#include "accel/core/params.h"
#include "accel/core/ray.h"

namespace ab {

/// The registry name of Embree (the mesh adapter registers under it; a scene uses Embree's own instancing
/// when both levels are named so).
inline constexpr const char* kEmbreeName = "embree";

/// The process-wide Embree device (created on first use); its memory monitor counts the bytes Embree holds.
RTCDevice embree_device();
/// Bytes Embree currently holds (from the device's memory monitor).
int64_t embree_bytes_in_use();
/// Restarts the high-water mark of the memory monitor at the bytes Embree holds now, and returns them.
int64_t embree_restart_peak();
/// The most bytes Embree held since the last embree_restart_peak().
int64_t embree_peak_bytes();

/// Embree's configuration: the build quality (RTC_BUILD_QUALITY_*), medium by default for meshes and scenes
/// alike (the reference every ratio_to_embree is measured against).
struct EmbreeConfig {
  RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM;  ///< quality=low|medium|high
  /// Reads `quality`.
  static EmbreeConfig read(Params& params);
};

/// A committed Embree scene holding `mesh` as geometry 0 (primID = triangle id; no geometry when the mesh is
/// empty), built at `quality` with `flags`. Throws InputError when Embree reports an error.
RTCScene commit_mesh_scene(const Mesh& mesh, RTCBuildQuality quality, RTCSceneFlags flags);
/// The same with the geometry's build quality apart from the scene's (RTC_BUILD_QUALITY_REFIT for a mesh
/// that is refitted when its vertices move).
RTCScene commit_mesh_scene(const Mesh& mesh, RTCBuildQuality quality, RTCSceneFlags flags,
                           RTCBuildQuality geometry_quality);

/// Moves geometry 0 of a scene made by commit_mesh_scene to `mesh`'s vertex positions (the same vertex count)
/// in place, and commits the geometry and the scene again: a refit when the geometry's quality is
/// RTC_BUILD_QUALITY_REFIT, a rebuild of the scene's quality otherwise. Nothing happens for an empty mesh.
void update_mesh_vertices(RTCScene scene, const Mesh& mesh);
/// A committed Embree scene holding a deforming mesh as geometry 0: one vertex buffer per time step
/// (rtcSetGeometryTimeStepCount; Embree interpolates them linearly per segment at the ray's time), the
/// triangle list of the first step. Throws InputError when Embree reports an error.
RTCScene commit_motion_mesh_scene(const std::vector<std::shared_ptr<const Mesh>>& steps,
                                  RTCBuildQuality quality, RTCSceneFlags flags);

/// Throws InputError naming `what` when the device has recorded an error (and clears it).
void check_embree_error(const char* what);

/// Converts a ray to Embree's RTCRayHit: tnear = tmin, tfar = `tfar` (the ray's tmax, or the best hit so
/// far), every mask bit, the ray's time (motion blur; 0 for ABRAYS01 rays), no hit.
inline RTCRayHit to_embree(const Ray& r, float tfar) {
  RTCRayHit rh;
  rh.ray.org_x = r.org.x;
  rh.ray.org_y = r.org.y;
  rh.ray.org_z = r.org.z;
  rh.ray.dir_x = r.dir.x;
  rh.ray.dir_y = r.dir.y;
  rh.ray.dir_z = r.dir.z;
  rh.ray.tnear = r.tmin;
  rh.ray.tfar = tfar;
  rh.ray.time = r.time;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}
/// The same over the whole of the ray's [tmin, tmax].
inline RTCRayHit to_embree(const Ray& r) {
  return to_embree(r, r.tmax);
}

/// True when rtcOccluded1 found a hit (Embree sets tfar to -inf then).
inline bool embree_occluded(const RTCRay& r) {
  return r.tfar == -kInf;
}

}  // namespace ab
