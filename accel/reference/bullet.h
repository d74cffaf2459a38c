// Bullet's btBvhTriangleMeshShape over one triangle mesh, behind the accelerator interface: an outside peer
// (a reference like Embree, not a structure of the project's own), registered as `bullet` when CMake finds
// bullet-float64.
#pragma once

#include <memory>

#include "accel/reference/peer_mesh.h"

namespace ab {

/// Bullet 3.24's quantized BVH (btBvhTriangleMeshShape, double-precision build) over the triangles of a
/// mesh, read in place as btIndexedMesh parts of at most 2^21 triangles, coordinates scaled inside Bullet
/// so the mesh spans about 1000 (Bullet has absolute margins). Bullet casts segments, so each ray is clipped
/// to the mesh bounds; the triangle ray-cast callback (flags kF_None) keeps the closest triangle the
/// project's kernel confirms (peer.h), else the closest Bullet reported. Any hit is the closest hit (Bullet
/// has no any-hit query). No traversal counters.
class BulletMesh final : public PeerMesh<BulletMesh> {
 public:
  /// Over prims (built by build()).
  BulletMesh(std::shared_ptr<const TrianglePrims> prims, const Config& config);
  /// Releases the shape.
  ~BulletMesh() override;
  BulletMesh(const BulletMesh&) = delete;
  BulletMesh& operator=(const BulletMesh&) = delete;

 protected:
  /// Builds Bullet's quantized BVH over the mesh.
  void do_build() override;
  /// Primitives, quantized nodes and the BVH's serialized size (what Bullet exposes).
  void gather_stats(BuildStats& stats) const override;

 private:
  friend class PeerMesh<BulletMesh>;
  struct Shape;
  void closest(const Ray& ray, Hit& best, uint32_t inst) const;
  /// Whether the closest hit exists (Bullet has no any-hit query).
  bool any(const Ray& ray) const;

  std::unique_ptr<Shape> shape_;
};

}  // namespace ab
