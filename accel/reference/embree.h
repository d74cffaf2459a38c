// Intel Embree 3 behind the accelerator interface: the reference and the bar to beat.
#pragma once

#include "accel/core/accelerator.h"
#include "accel/core/params.h"
#include "accel/core/primitives.h"

#include <embree3/rtcore.h>

#include <memory>

namespace ab {

/// The process-wide Embree device (created on first use; its memory monitor counts bytes per build).
RTCDevice embree_device();
/// Bytes Embree currently holds (from the device's memory monitor).
int64_t embree_bytes_in_use();

/// Embree over one triangle mesh: primID = triangle id, geomID 0. Parameters: quality = low|medium|high
/// (RTC_BUILD_QUALITY_*), default medium. Counters are not available (Embree does not expose them): the
/// counted entry points report zeros.
class EmbreeMesh final : public Accelerator {
 public:
  /// Reads `quality` from params.
  EmbreeMesh(std::shared_ptr<const TrianglePrims> prims, Params& params);
  ~EmbreeMesh() override;
  EmbreeMesh(const EmbreeMesh&) = delete;
  EmbreeMesh& operator=(const EmbreeMesh&) = delete;

  std::string name() const override { return "embree"; }
  nlohmann::json config() const override { return config_; }
  AABB bounds() const override { return prims_->bounds(); }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const override;
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out) const override;
  void intersect_counted(std::span<const Ray> rays, std::span<Hit> hits, RayCounters& total) const override;
  void occluded_counted(std::span<const Ray> rays, std::span<uint8_t> out, RayCounters& total) const override;
  void intersect_one(const Ray& ray, Hit& best, uint32_t inst, RayCounters* counters) const override;
  bool occluded_one(const Ray& ray, RayCounters* counters) const override;

  /// The committed Embree scene (for adapters that instance it).
  RTCScene scene() const { return scene_; }

 protected:
  void do_build() override;

 private:
  std::shared_ptr<const TrianglePrims> prims_;
  nlohmann::json config_;
  RTCBuildQuality quality_ = RTC_BUILD_QUALITY_MEDIUM;
  RTCScene scene_ = nullptr;
};

/// Converts a ray to Embree's RTCRayHit (tnear = tmin, tfar = tmax, mask all, no time).
inline RTCRayHit to_embree(const Ray& r) {
  RTCRayHit rh;
  rh.ray.org_x = r.org.x;
  rh.ray.org_y = r.org.y;
  rh.ray.org_z = r.org.z;
  rh.ray.dir_x = r.dir.x;
  rh.ray.dir_y = r.dir.y;
  rh.ray.dir_z = r.dir.z;
  rh.ray.tnear = r.tmin;
  rh.ray.tfar = r.tmax;
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

}  // namespace ab
