// Bullet's btBvhTriangleMeshShape over one triangle mesh, behind the accelerator interface: an outside peer
// (a reference like Embree, not a structure of the project's own), registered as `bullet` when CMake finds
// bullet-float64.
#pragma once

#include <memory>

#include "accel/core/accelerator.h"
#include "accel/core/params.h"
#include "accel/core/primitives.h"

namespace ab {

/// Bullet 3.24's quantized BVH (btBvhTriangleMeshShape, double-precision build) over the triangles of a
/// mesh, read in place as btIndexedMesh parts of at most 2^21 triangles, coordinates scaled inside Bullet
/// so the mesh spans about 1000 (Bullet has absolute margins). Bullet casts segments, so each ray is clipped
/// to the mesh bounds; the triangle ray-cast callback (flags kF_None) keeps the closest triangle the
/// project's kernel confirms (peer.h), else the closest Bullet reported. Any hit is the closest hit (Bullet
/// has no any-hit query). No traversal counters.
class BulletMesh final : public AcceleratorBase<BulletMesh> {
 public:
  using Prims = TrianglePrims;  ///< over triangle meshes only
  /// Bullet's mesh shape is built with its defaults: no parameters.
  struct Config {
    /// Reads nothing.
    static Config read(Params&) { return {}; }
  };

  /// Over prims (built by build()).
  BulletMesh(std::shared_ptr<const TrianglePrims> prims, const Config& config);
  /// Releases the shape.
  ~BulletMesh() override;
  BulletMesh(const BulletMesh&) = delete;
  BulletMesh& operator=(const BulletMesh&) = delete;

  /// Bounds of the mesh.
  AABB bounds() const override { return prims_->bounds(); }

  /// Closest hit of one ray, kept in best by the acceptance rule (counters stay zero).
  template <bool kCount>
  void intersect_ray(const Ray& ray, Hit& best, uint32_t inst, RayCounters&) const {
    closest(ray, best, inst);
  }
  /// Any hit of one ray: whether the closest hit exists.
  template <bool kCount>
  bool occluded_ray(const Ray& ray, RayCounters&) const {
    Hit h;
    closest(ray, h, kInvalidId);
    return h.found();
  }

 protected:
  /// Builds Bullet's quantized BVH over the mesh.
  void do_build() override;
  /// Primitives, quantized nodes and the BVH's serialized size (what Bullet exposes).
  void gather_stats(BuildStats& stats) const override;

 private:
  struct Shape;
  void closest(const Ray& ray, Hit& best, uint32_t inst) const;

  std::shared_ptr<const TrianglePrims> prims_;
  std::unique_ptr<Shape> shape_;
};

}  // namespace ab
