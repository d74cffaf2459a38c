// The two-level structure of a scene: one bottom-level structure per base mesh (built once however
// many instances use it) and a top-level structure over the instances' world bounds.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "accel/core/accelerator.h"
#include "accel/core/instances.h"
#include "accel/core/params.h"
#include "accel/reference/embree_scene.h"
#include "tracer/scene.h"
#include "tracer/scene_motion.h"

namespace ab {

/// Two levels of registered structures. Hits: inst = instance index (document order), prim =
/// triangle id in that instance's base mesh. With the camera's shutter open, a base mesh that deforms
/// during it has a bottom over its time steps (MotionTrianglePrims) and an instance that moves carries its
/// matrices at the time steps (motion blur: tracer/scene_motion.h); update() then declines (rebuild).
/// Parameters: `top.k=v` goes to the top level only, `bottom.k=v` to the bottom level only, plain `k=v` to
/// both.
class SceneAccelerator final : public Accelerator {
 public:
  /// Creates (does not build) the structures; throws UnknownAccelerator or ParamError.
  SceneAccelerator(std::shared_ptr<const Scene> scene, std::string top, std::string bottom,
                   const Params& params);

  std::string name() const override;
  nlohmann::json config() const override;
  AABB bounds() const override { return bounds_; }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const override {
    top_->intersect(rays, hits);
  }
  void occluded(std::span<const Ray> rays, std::span<uint8_t> out) const override {
    top_->occluded(rays, out);
  }
  void intersect_counted(std::span<const Ray> rays, std::span<Hit> hits, RayCounters& total) const override {
    top_->intersect_counted(rays, hits, total);
  }
  void occluded_counted(std::span<const Ray> rays, std::span<uint8_t> out,
                        RayCounters& total) const override {
    top_->occluded_counted(rays, out, total);
  }
  void intersect_one(const Ray& ray, Hit& best, uint32_t inst, RayCounters* counters) const override {
    top_->intersect_one(ray, best, inst, counters);
  }
  bool occluded_one(const Ray& ray, RayCounters* counters) const override {
    return top_->occluded_one(ray, counters);
  }

  /// How one level follows a frame in update().
  enum class LevelUpdate { kRefit, kRebuild };
  /// Moves the built structure to `frame` (the same scene at another time: same meshes, triangle lists and
  /// instances): each base mesh whose geometry changed is refit or rebuilt as `bottom` says (unchanged ones
  /// are kept), then the top level over the new transforms as `top` says. Timed alone into
  /// stats().build_seconds (tracer/update_strategy.cpp). False when a level does not refit or the frame does
  /// not match; the structure must then be rebuilt.
  bool update(std::shared_ptr<const Scene> frame, LevelUpdate bottom, LevelUpdate top);

  /// The built bottom-level structure of base mesh m.
  const Accelerator& bottom(size_t m) const { return *bottoms_[m]; }
  /// The built top-level structure.
  const Accelerator& top() const { return *top_; }

 protected:
  void do_build() override;

 private:
  void aggregate_stats();
  /// The instances of scene_ over the current bottoms.
  std::vector<Instance> make_instances() const;

  std::shared_ptr<const Scene> scene_;
  SceneMotion motion_;  ///< what moves during the shutter (nothing when it is closed)
  std::string top_name_, bottom_name_;
  Params top_params_, bottom_params_;
  std::vector<std::shared_ptr<Accelerator>> bottoms_;
  std::shared_ptr<const InstancePrims> instances_;
  std::unique_ptr<Accelerator> top_;
  AABB bounds_;
};

/// The parameters of one level: plain keys and keys with `prefix.` (prefix removed); keys of the
/// other level are dropped.
Params level_params(const Params& params, const std::string& prefix, const std::string& other);

/// What Embree's own instancing is given of a scene (embree_scene.h): its meshes at the scene's time, and
/// each instance's mesh and object-to-world matrix in document order.
void embree_scene_inputs(const Scene& scene, std::vector<std::shared_ptr<const Mesh>>& meshes,
                         std::vector<EmbreeInstanceInput>& instances);

/// Creates (not builds) the accelerator for a scene: Embree's own two-level instancing when both
/// levels are `embree`, a SceneAccelerator otherwise. Empty top/bottom fall back to `name`.
std::unique_ptr<Accelerator> make_scene_accelerator(std::shared_ptr<const Scene> scene,
                                                    const std::string& name, const Params& params,
                                                    const std::string& top = "",
                                                    const std::string& bottom = "");

}  // namespace ab
