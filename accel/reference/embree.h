// Intel Embree 3 over one triangle mesh, behind the accelerator interface: the reference and the bar to beat.
#pragma once

#include <memory>

#include "accel/core/accelerator.h"
#include "accel/core/primitives.h"
#include "accel/reference/embree_device.h"

namespace ab {

/// Embree over one triangle mesh: primID = triangle id, geomID 0, registered as `embree` (a reference, not a
/// structure of the project's own). Parameter: quality = low|medium|high (EmbreeConfig). Counters are not
/// available (Embree does not expose them): the counted entry points report zeros.
class EmbreeMesh final : public Accelerator {
 public:
  using Prims = TrianglePrims;  ///< over triangle meshes only (a scene uses embree_scene.h)
  using Config = EmbreeConfig;  ///< the build quality

  /// Over prims, built at config.quality.
  EmbreeMesh(std::shared_ptr<const TrianglePrims> prims, const Config& config);
  /// Releases the Embree scene; not copyable (it owns it).
  ~EmbreeMesh() override;
  EmbreeMesh(const EmbreeMesh&) = delete;
  EmbreeMesh& operator=(const EmbreeMesh&) = delete;

  /// Bounds of the mesh.
  AABB bounds() const override { return prims_->bounds(); }

  /// The accelerator interface, each ray through rtcIntersect1 / rtcOccluded1 (counters stay zero).
  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const override;
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out) const override;
  void intersect_counted(std::span<const Ray> rays, std::span<Hit> hits, RayCounters& total) const override;
  void occluded_counted(std::span<const Ray> rays, std::span<uint8_t> out, RayCounters& total) const override;
  void intersect_one(const Ray& ray, Hit& best, uint32_t inst, RayCounters* counters) const override;
  bool occluded_one(const Ray& ray, RayCounters* counters) const override;

  /// Moves the mesh to `prims` (the same triangles, new vertex positions) and commits it again in a dynamic
  /// scene (RTC_SCENE_FLAG_DYNAMIC) whose geometry has build quality `quality`: RTC_BUILD_QUALITY_REFIT
  /// refits Embree's BVH (in a low-quality scene: Embree honours a geometry's quality only there), low or
  /// medium rebuild it (in a scene of that quality). The first call (or a change of quality or vertex count)
  /// makes the dynamic scene; later calls update the vertex buffer in place. Not timed here.
  void commit_frame(std::shared_ptr<const TrianglePrims> prims, RTCBuildQuality quality);

  /// The committed Embree scene (for adapters that instance it).
  RTCScene scene() const { return scene_; }

 protected:
  /// Uploads the mesh and commits the scene; records the bytes Embree's memory monitor saw it take.
  void do_build() override;
  void gather_stats(BuildStats& stats) const override;
  /// commit_frame at RTC_BUILD_QUALITY_REFIT.
  bool do_refit_triangles(std::shared_ptr<const TrianglePrims> prims) override;

 private:
  std::shared_ptr<const TrianglePrims> prims_;
  Config config_;
  RTCScene scene_ = nullptr;
  bool dynamic_ = false;                                         ///< scene_ is commit_frame's dynamic scene
  RTCBuildQuality geometry_quality_ = RTC_BUILD_QUALITY_MEDIUM;  ///< its geometry's quality
};

}  // namespace ab
